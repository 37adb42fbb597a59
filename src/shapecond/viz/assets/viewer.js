// shapecond's HTML viewer: draws the scenes of shapecond.viz.scene embedded in the page.
// Part of shapecond (MIT).  three.js is loaded from the page itself (script#sc-three, turned
// into a module through a blob URL), so the page needs no network.  Each
// <div class="sc-viewer"> holds a <script type="application/json"> with one scene.
"use strict";
(function () {
  const PI = Math.PI;

  function buffer(s) {
    const b = atob(s), u = new Uint8Array(b.length);
    for (let i = 0; i < b.length; i++) u[i] = b.charCodeAt(i);
    return u.buffer;
  }
  const typed = (s, T) => (s === null || s === undefined ? null : new T(buffer(s)));

  function fmt(v) {
    if (v === null || v === undefined || Number.isNaN(v)) return "-";
    if (!Number.isFinite(v)) return v > 0 ? "inf" : "-inf";
    if (Number.isInteger(v)) return String(v);
    return String(Number(v.toPrecision(4)));
  }

  function el(tag, cls, text) {
    const e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined) e.textContent = text;
    return e;
  }

  const MESH_VS = `in vec3 position; in vec3 rgb;
uniform mat4 modelViewMatrix; uniform mat4 projectionMatrix;
out vec3 vColour; out vec3 vView;
void main() { vec4 mv = modelViewMatrix * vec4(position, 1.0); vView = mv.xyz; vColour = rgb;
  gl_Position = projectionMatrix * mv; }`;
  // headlight shading of the PNGs: colour * (ambient + diffuse |n.v|), n the face normal
  const MESH_FS = `precision highp float; in vec3 vColour; in vec3 vView;
uniform float ambient; uniform float diffuse; out vec4 outColour;
void main() { vec3 n = normalize(cross(dFdx(vView), dFdy(vView)));
  outColour = vec4(vColour * (ambient + diffuse * abs(n.z)), 1.0); }`;
  const POINT_VS = `in vec3 position; in vec3 rgb;
uniform mat4 modelViewMatrix; uniform mat4 projectionMatrix; uniform float size;
out vec3 vColour;
void main() { vColour = rgb; gl_PointSize = size; gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }`;
  const POINT_FS = `precision highp float; in vec3 vColour; out vec4 outColour;
void main() { if (length(gl_PointCoord - 0.5) > 0.5) discard; outColour = vec4(vColour, 1.0); }`;

  // the material of a mesh (faces) or point cloud coloured by its "rgb" attribute
  function material(T, faces, shading, pointSize) {
    return new T.RawShaderMaterial({
      glslVersion: T.GLSL3, side: T.DoubleSide,
      uniforms: { ambient: { value: shading[0] }, diffuse: { value: shading[1] }, size: { value: pointSize } },
      vertexShader: faces ? MESH_VS : POINT_VS, fragmentShader: faces ? MESH_FS : POINT_FS,
    });
  }

  // the camera of shapecond.viz.render.view_rotation: rows right, up, toward the viewer
  function viewFrame(T, elev, azim) {
    const e = elev * PI / 180, a = azim * PI / 180;
    const toward = new T.Vector3(Math.cos(e) * Math.cos(a), Math.cos(e) * Math.sin(a), Math.sin(e));
    const right = new T.Vector3(-Math.sin(a), Math.cos(a), 0);
    return { toward, right, up: new T.Vector3().crossVectors(toward, right) };
  }

  // half-extents of a bounding box seen from the view f (the PNGs' panels are fitted alike)
  function fitBox(b, c, f) {
    let w = 1e-9, h = 1e-9;
    for (const x of [b.min.x, b.max.x]) for (const y of [b.min.y, b.max.y]) for (const z of [b.min.z, b.max.z]) {
      const dx = x - c.x, dy = y - c.y, dz = z - c.z;
      w = Math.max(w, Math.abs(dx * f.right.x + dy * f.right.y + dz * f.right.z));
      h = Math.max(h, Math.abs(dx * f.up.x + dy * f.up.y + dz * f.up.z));
    }
    return [w, h];
  }

  // an orthographic camera looking at centre from f.toward, showing the half-extents fitted (zoomed)
  function aim(c, centre, radius, f, fitted, asp, zoom) {
    const half = 1.08 * Math.max(fitted[1], fitted[0] / asp) / zoom;
    c.left = -half * asp; c.right = half * asp; c.top = half; c.bottom = -half;
    c.near = radius * 0.01; c.far = radius * 10;
    c.position.copy(centre).addScaledVector(f.toward, 3 * radius);
    c.up.copy(f.up); c.lookAt(centre); c.updateProjectionMatrix(); c.updateMatrixWorld();
  }

  class Viewer {
    constructor(T, root, data) {
      this.T = T; this.root = root; this.d = data;
      this.n = data.n;
      this.pos = typed(data.positions, Float32Array);
      this.faces = typed(data.faces, Uint32Array);
      this.ids = typed(data.ids, Int32Array);
      this.partner = typed(data.partner, Int32Array);
      this.layers = data.layers.map((l) => Object.assign({}, l, {
        rgb: typed(l.colours, Uint8Array), vals: typed(l.values, Float32Array), seg: typed(l.segments, Float32Array),
      }));
      this.elev = data.views[0][0]; this.azim = data.views[0][1]; this.zoom = 1;
      this.current = -1; this.frames = 0; this.firstFrame = null; this.hovered = -1;
      this.extra = [];  // markers drawn on every colouring: suggestions, picked landmarks
      this.dom(); this.three(); this.suggestions();
      if (data.picking && data.parts.length === 2) this.picker = new Picker(this, data.picking);
      this.setLayer(0); this.events(); this.draw();
    }

    dom() {
      const r = this.root;
      this.bar = el("div", "sc-bar"); this.stage = el("div", "sc-stage");
      this.canvas = el("canvas"); this.labels = el("div", "sc-labels"); this.hover = el("div", "sc-hover");
      this.scale = el("div", "sc-scale"); this.side = el("div", "sc-side");
      this.stage.append(this.canvas, this.labels, this.hover);
      const main = el("div", "sc-main"); main.append(this.stage, this.side);
      r.append(this.bar, main, this.scale);
      if (this.layers.length > 1) {
        this.layerButtons = this.layers.map((l, k) => {
          const b = el("button", "sc-layer", l.label || `colouring ${k + 1}`);
          b.onclick = () => this.setLayer(k); this.bar.append(b); return b;
        });
        this.bar.append(el("span", "sc-sep", "|"));
      }
      this.d.views.forEach((v, k) => {
        const b = el("button", "sc-view", this.d.view_labels[k]);
        b.onclick = () => this.setView(k); this.bar.append(b);
      });
      this.bar.append(el("span", "sc-help", "drag: turn, wheel: zoom, hover: vertex id and value"));
    }

    three() {
      const T = this.T;
      this.renderer = new T.WebGLRenderer({ canvas: this.canvas, antialias: true, preserveDrawingBuffer: true });
      this.renderer.outputColorSpace = T.LinearSRGBColorSpace;
      this.renderer.setClearColor(0xffffff, 1);
      this.renderer.setPixelRatio(window.devicePixelRatio || 1);
      this.scene = new T.Scene();
      const g = new T.BufferGeometry();
      g.setAttribute("position", new T.BufferAttribute(this.pos, 3));
      this.colour = new T.BufferAttribute(new Uint8Array(this.n * 3), 3, true);
      g.setAttribute("rgb", this.colour);
      if (this.faces) g.setIndex(new T.BufferAttribute(this.faces, 1));
      g.computeBoundingSphere();
      this.centre = g.boundingSphere.center.clone(); this.radius = g.boundingSphere.radius || 1;
      g.computeBoundingBox(); this.box = g.boundingBox;
      const mat = material(T, this.faces, this.d.shading, this.d.point_size);
      this.object = this.faces ? new T.Mesh(g, mat) : new T.Points(g, mat);
      this.scene.add(this.object);
      this.camera = new T.OrthographicCamera(-1, 1, 1, -1, this.radius * 0.01, this.radius * 10);
      this.raycaster = new T.Raycaster();
      this.raycaster.params.Points.threshold = this.radius * 0.01;
      this.groups = this.layers.map((l) => this.overlay(l));
      const mark = (c) => new T.Mesh(new T.SphereGeometry(this.radius * 0.012, 12, 8),
        new T.MeshBasicMaterial({ color: c }));
      this.mark = mark(0x111111); this.partnerMark = mark(0x2255ff);
      this.mark.visible = this.partnerMark.visible = false;
      this.scene.add(this.mark, this.partnerMark);
    }

    overlay(layer) {
      const T = this.T, group = new T.Group();
      layer.marks = layer.landmarks.map((lm) => {
        const s = new T.Mesh(new T.SphereGeometry(this.radius * 0.018, 16, 12),
          new T.MeshBasicMaterial({ color: new T.Color(lm.colour) }));
        s.position.set(...lm.position); group.add(s);
        const label = el("div", "sc-label", lm.label); label.style.display = "none";
        this.labels.append(label);
        return { lm, label };
      });
      if (layer.seg) {
        const g = new T.BufferGeometry();
        g.setAttribute("position", new T.BufferAttribute(layer.seg, 3));
        group.add(new T.LineSegments(g, new T.LineBasicMaterial({ color: 0x000000, transparent: true, opacity: 0.7 })));
      }
      group.visible = false; this.scene.add(group);
      return group;
    }

    setLayer(k) {
      if (this.current >= 0) {
        this.groups[this.current].visible = false;
        this.layers[this.current].marks.forEach((m) => (m.label.style.display = "none"));
      }
      this.current = k;
      const l = this.layers[k];
      this.colour.array.set(l.rgb); this.colour.needsUpdate = true;
      this.groups[k].visible = true;
      if (this.layerButtons) this.layerButtons.forEach((b, i) => b.classList.toggle("sc-on", i === k));
      this.showScale(l); this.showSide(l); this.showHover(); this.draw();
    }

    showScale(l) {
      this.scale.innerHTML = "";
      if (!l.colorbar) { this.scale.style.display = "none"; return; }
      const c = l.colorbar; this.scale.style.display = "";
      const ramp = el("div", "sc-ramp");
      ramp.style.background = `linear-gradient(to right, ${c.stops.join(", ")})`;
      const ticks = el("div", "sc-ticks");
      ticks.append(el("span", "", fmt(c.lo)), el("span", "", fmt((c.lo + c.hi) / 2)), el("span", "", fmt(c.hi)));
      this.scale.append(el("div", "sc-caption", c.label || ""), ramp, ticks);
    }

    showSide(l) {
      this.side.innerHTML = "";
      if (!l.landmarks.length) { this.side.style.display = "none"; return; }
      this.side.style.display = "";
      this.side.append(el("div", "sc-caption", "landmarks, in order"));
      const ol = el("ol", "sc-landmarks");
      l.landmarks.forEach((lm) => {
        const li = el("li", "", `${lm.label}. ${lm.name}` + (lm.note ? ` — ${lm.note}` : ""));
        li.style.borderLeft = `6px solid ${lm.colour}`;
        li.onmouseenter = () => this.pick(lm.vertex); ol.append(li);
      });
      this.side.append(ol);
    }

    setView(k) { [this.elev, this.azim] = this.d.views[k]; this.zoom = 1; this.fitted = null; this.draw(); }

    frame() { return viewFrame(this.T, this.elev, this.azim); }

    place() {
      const w = this.stage.clientWidth || 600, h = this.stage.clientHeight || 400;
      if (this.size !== `${w}x${h}`) { this.renderer.setSize(w, h, false); this.size = `${w}x${h}`; }
      const f = this.frame();
      if (!this.fitted) this.fitted = fitBox(this.box, this.centre, f);  // kept while turning: no jumps
      aim(this.camera, this.centre, this.radius, f, this.fitted, w / h, this.zoom);
      return f;
    }

    draw() {
      const f = this.place();
      this.renderer.render(this.scene, this.camera);
      this.frames += 1;
      if (this.firstFrame === null) requestAnimationFrame(() => { if (this.firstFrame === null) this.firstFrame = performance.now(); });
      const rect = this.canvas.getBoundingClientRect(), stage = this.stage.getBoundingClientRect();
      for (const { lm, label } of this.layers[this.current].marks.concat(this.extra)) {
        const facing = lm.normal === null || (lm.normal[0] * f.toward.x + lm.normal[1] * f.toward.y +
          lm.normal[2] * f.toward.z) > this.d.facing;
        const p = this.screen(lm.position, rect);
        label.style.display = facing ? "" : "none";
        label.style.left = `${p.x - stage.left + 6}px`; label.style.top = `${p.y - stage.top - 16}px`;
      }
    }

    screen(xyz, rect) {
      const v = new this.T.Vector3(...xyz).project(this.camera);
      rect = rect || this.canvas.getBoundingClientRect();
      return { x: rect.left + (v.x + 1) / 2 * rect.width, y: rect.top + (1 - v.y) / 2 * rect.height };
    }

    // client coordinates of display vertex i (tests move the mouse there)
    screenOf(i) { return this.screen([this.pos[3 * i], this.pos[3 * i + 1], this.pos[3 * i + 2]]); }

    indexOfId(id, part) {
      const [lo, hi] = part === undefined || !this.d.parts.length ? [0, this.n] : this.d.parts[part].slice(1);
      for (let i = lo; i < hi; i++) if ((this.ids ? this.ids[i] : i) === id) return i;
      return -1;
    }

    partName(i) {
      for (const [name, lo, hi] of this.d.parts) if (i >= lo && i < hi) return name + " ";
      return "";
    }

    vertexAt(x, y) {
      const rect = this.canvas.getBoundingClientRect(), T = this.T;
      const ndc = new T.Vector2((x - rect.left) / rect.width * 2 - 1, -((y - rect.top) / rect.height) * 2 + 1);
      this.raycaster.setFromCamera(ndc, this.camera);
      const hit = this.raycaster.intersectObject(this.object, false)[0];
      if (!hit) return -1;
      if (!this.faces) return hit.index;
      let best = -1, bd = Infinity;
      for (const v of [hit.face.a, hit.face.b, hit.face.c]) {
        const dx = this.pos[3 * v] - hit.point.x, dy = this.pos[3 * v + 1] - hit.point.y, dz = this.pos[3 * v + 2] - hit.point.z;
        const d = dx * dx + dy * dy + dz * dz;
        if (d < bd) { bd = d; best = v; }
      }
      return best;
    }

    partOf(i) {
      return this.d.parts.findIndex(([, lo, hi]) => i >= lo && i < hi);
    }

    // a marker on every colouring: a sphere (or a diamond), its number beside it
    marker(position, colour, text, diamond) {
      const T = this.T, r = this.radius * (diamond ? 0.026 : 0.018);
      const m = new T.Mesh(diamond ? new T.OctahedronGeometry(r) : new T.SphereGeometry(r, 16, 12),
        new T.MeshBasicMaterial({ color: new T.Color(colour) }));
      m.position.set(...position);
      const label = el("div", "sc-label", text); label.style.color = colour; this.labels.append(label);
      const mark = { lm: { position, normal: null }, label, mesh: m };
      this.extra.push(mark);
      return mark;
    }

    unmark(mark) {
      this.extra = this.extra.filter((m) => m !== mark); mark.label.remove();
      mark.mesh.geometry.dispose(); mark.mesh.removeFromParent();
    }

    // suggested points (viz.pages.MatchFields.suggestions): diamonds S1, S2, ... and their list
    suggestions() {
      const list = this.d.suggestions || [];
      if (!list.length) return;
      const box = el("div", "sc-suggest");
      box.append(el("div", "sc-caption", "suggested next landmarks (diamonds)" +
        (this.d.picking ? "; click one here to pick it on the source" : "")));
      const ol = el("ol", "sc-landmarks");
      for (const s of list) {
        this.scene.add(this.marker(s.position, SUGGEST_COLOUR, s.label, true).mesh);
        const li = el("li", "sc-suggestion", `${s.label}. ${s.name}` + (s.note ? ` — ${s.note}` : ""));
        li.style.borderLeft = `6px solid ${SUGGEST_COLOUR}`;
        li.onclick = () => { if (this.picker) this.picker.click(this.indexOfId(s.id, 0)); };
        ol.append(li);
      }
      box.append(ol); this.root.append(box);
    }

    pick(i) { this.hovered = i; this.showHover(); this.draw(); }

    showHover() {
      const i = this.hovered, l = this.layers[this.current];
      const at = (m, v) => { m.visible = v >= 0; if (v >= 0) m.position.set(this.pos[3 * v], this.pos[3 * v + 1], this.pos[3 * v + 2]); };
      at(this.mark, i);
      const j = i >= 0 && this.partner ? this.partner[i] : -1;
      at(this.partnerMark, j);
      if (i < 0) { this.hover.style.display = "none"; this.hover.removeAttribute("data-vertex"); return; }
      const id = this.ids ? this.ids[i] : i;
      let text = `${this.partName(i)}vertex ${id}`;
      if (l.vals) text += `\n${l.value_name || "value"}: ${fmt(l.vals[i])}`;
      if (j >= 0) text += `\n→ ${this.partName(j)}vertex ${this.ids ? this.ids[j] : j}`;
      this.hover.textContent = text; this.hover.style.display = "block";
      this.hover.setAttribute("data-vertex", String(id));
    }

    events() {
      const c = this.canvas;
      let drag = null, pending = false, last = null;
      let down = null;
      c.addEventListener("pointerdown", (e) => {
        drag = down = [e.clientX, e.clientY]; c.setPointerCapture(e.pointerId);
      });
      c.addEventListener("pointerup", (e) => {
        drag = null; c.releasePointerCapture(e.pointerId);
        const still = down && Math.hypot(e.clientX - down[0], e.clientY - down[1]) < 5;
        if (still && this.picker) this.picker.click(this.vertexAt(e.clientX, e.clientY));
        down = null;
      });
      c.addEventListener("pointermove", (e) => {
        if (drag) {
          this.azim -= (e.clientX - drag[0]) * 0.4;
          this.elev = Math.max(-90, Math.min(90, this.elev + (e.clientY - drag[1]) * 0.4));
          drag = [e.clientX, e.clientY]; this.draw(); return;
        }
        last = [e.clientX, e.clientY];
        if (!pending) {
          pending = true;
          requestAnimationFrame(() => { pending = false; const i = this.vertexAt(...last); if (i !== this.hovered) this.pick(i); });
        }
      });
      c.addEventListener("pointerleave", () => { if (!drag) this.pick(-1); });
      c.addEventListener("wheel", (e) => {
        e.preventDefault(); this.zoom = Math.max(0.2, Math.min(50, this.zoom * Math.exp(-e.deltaY * 0.001))); this.draw();
      }, { passive: false });
      if (window.ResizeObserver) new ResizeObserver(() => this.draw()).observe(this.stage);
    }
  }

  const SUGGEST_COLOUR = "#c01fc0", PENDING_COLOUR = "#ff8c00";

  // Landmark pairs picked by clicking a source vertex, then a target vertex (viz.pages.match_picking):
  // numbered after the command line's pairs, with the command that re-runs the match with all of them.
  class Picker {
    constructor(v, p) {
      this.v = v; this.p = p; this.pairs = []; this.pending = -1; this.marks = [];
      this.lines = new v.T.Group(); v.scene.add(this.lines);
      const box = el("div", "sc-pick"), row = el("div", "sc-pick-row");
      this.state = el("span", "sc-pick-state");
      this.undoButton = el("button", "sc-undo", "undo last pair"); this.undoButton.onclick = () => this.undo();
      this.copyButton = el("button", "sc-copy", "copy command"); this.copyButton.onclick = () => this.copy();
      this.files = ["source", "target"].map((side) => {
        const a = el("a", "sc-file", `landmark file (${side})`);
        a.download = `landmarks_${side}.txt`; return a;
      });
      row.append(this.undoButton, this.copyButton, ...this.files, this.state);
      this.command = el("pre", "sc-command");
      box.append(el("div", "sc-caption", "pick landmarks: click a source vertex, then its target vertex; " +
        "the command re-runs the match with every pair so far"), this.command, row);
      if (p.placeholders.length) {
        box.append(el("div", "sc-notes", `${p.placeholders.map((k) => p[k]).join(", ")}: stand-ins for the ` +
          "paths of this match, which the page was written without"));
      }
      v.root.append(box);
      this.update("");
    }

    id(i) { return this.v.ids ? this.v.ids[i] : i; }

    // every pair so far as [source ids, target ids]: the command line's, then the picked ones
    ids() {
      const all = this.p.pairs.concat(this.pairs.map(([s, t]) => [this.id(s), this.id(t)]));
      return [all.map((q) => q[0]), all.map((q) => q[1])];
    }

    text() {
      const [s, t] = this.ids(), p = this.p;
      if (!s.length) return "(no landmark pair yet)";
      return `shapecond match ${p.source} ${p.target} --landmarks-source ${s.join(",")} ` +
        `--landmarks-target ${t.join(",")} -o ${p.output} --html ${p.html}` + (p.options ? ` ${p.options}` : "");
    }

    click(i) {
      const part = i < 0 ? -1 : this.v.partOf(i);
      if (part === 0) { this.pending = i; this.update(`source vertex ${this.id(i)}: now click its target vertex`); }
      else if (part === 1 && this.pending >= 0) {
        this.pairs.push([this.pending, i]); this.pending = -1;
        this.update(`pair ${this.p.pairs.length + this.pairs.length} added`);
      } else if (part === 1) this.update("click a source vertex first");
    }

    undo() {
      if (this.pending >= 0) this.pending = -1; else this.pairs.pop();
      this.update("");
    }

    copy() {
      const text = this.text(), done = () => this.update("command copied"), v = this.command;
      const fallback = () => {
        const r = document.createRange(); r.selectNodeContents(v);
        const sel = window.getSelection(); sel.removeAllRanges(); sel.addRange(r);
        let ok = false;
        try { ok = document.execCommand("copy"); } catch (err) { ok = false; }
        this.update(ok ? "command copied" : "command selected: press Ctrl+C");
      };
      if (navigator.clipboard && window.isSecureContext) navigator.clipboard.writeText(text).then(done, fallback);
      else fallback();
    }

    redraw() {
      const v = this.v, T = v.T, [first, rest] = v.d.marker_colours;
      const at = (i) => Array.from(v.pos.slice(3 * i, 3 * i + 3));
      this.marks.forEach((m) => v.unmark(m)); this.marks = [];
      this.lines.children.slice().forEach((c) => { c.geometry.dispose(); this.lines.remove(c); });
      this.pairs.forEach(([s, t], k) => {
        const rank = this.p.pairs.length + k, colour = rank < 3 ? first : rest;
        for (const i of [s, t]) {
          const m = v.marker(at(i), colour, String(rank + 1)); this.marks.push(m); this.lines.add(m.mesh);
        }
        const g = new T.BufferGeometry().setFromPoints([new T.Vector3(...at(s)), new T.Vector3(...at(t))]);
        this.lines.add(new T.LineSegments(g, new T.LineBasicMaterial({ color: 0x000000 })));
      });
      if (this.pending >= 0) {
        const m = v.marker(at(this.pending), PENDING_COLOUR, "?"); this.marks.push(m); this.lines.add(m.mesh);
      }
    }

    update(message) {
      const [s, t] = this.ids();
      const file = (a) => "data:text/plain;charset=utf-8," + encodeURIComponent(a.join(",") + "\n");
      this.command.textContent = this.text();
      this.command.setAttribute("data-source-ids", s.join(","));
      this.command.setAttribute("data-target-ids", t.join(","));
      this.files[0].href = file(s); this.files[1].href = file(t);
      this.undoButton.disabled = !this.pairs.length && this.pending < 0;
      this.state.textContent = message;
      this.redraw();
      if (this.v.current >= 0) this.v.draw();
    }
  }

  // Small turnable views of many maps (shapecond.viz.mapview: report.html of a matched batch).  A browser
  // keeps only about 16 live WebGL contexts, so ONE renderer draws every view and each is copied to its
  // own 2-D canvas: when it scrolls into sight, and while it is turned (drag; double-click: back to the
  // first view).  Each div.sc-mapview shows the payload of the script.sc-mapdata of the same data-view,
  // with its colourings transfer and doubt.
  const MAPVIEW_LAYERS = [["transfer", "transfer"], ["doubt", "doubt"]];

  class MapViews {
    constructor(T) {
      this.T = T; this.views = []; this.shapes = new Map(); this.materials = new Map(); this.frames = 0;
      this.renderer = new T.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
      this.renderer.outputColorSpace = T.LinearSRGBColorSpace;
      this.renderer.setClearColor(0xffffff, 1);
      this.scene = new T.Scene();
      this.camera = new T.OrthographicCamera(-1, 1, 1, -1, 0.01, 10);
      this.mark = new T.Mesh(new T.OctahedronGeometry(1), new T.MeshBasicMaterial({ color: SUGGEST_COLOUR }));
      this.scene.add(this.mark);
      const data = new Map();
      document.querySelectorAll("script.sc-mapdata").forEach((s) => data.set(s.dataset.view, s));
      this.seen = window.IntersectionObserver ? new IntersectionObserver((entries) => entries.forEach((e) => {
        if (e.isIntersecting) { this.seen.unobserve(e.target); this.draw(e.target.scView); }
      }), { rootMargin: "200px" }) : null;
      document.querySelectorAll(".sc-mapview").forEach((root) => {
        const script = data.get(root.dataset.view);
        if (!script) { root.append(el("span", "sc-error", "no view")); return; }
        const v = this.add(root, script);
        if (this.seen) this.seen.observe(root); else this.draw(v);
      });
    }

    add(root, script) {
      const canvas = el("canvas"), bar = el("div", "sc-bar"), scale = el("div", "sc-scale");
      const v = { root, script, canvas, scale, layer: 0, frames: 0, zoom: 1, fitted: null, buttons: [] };
      root.scView = v;
      MAPVIEW_LAYERS.forEach(([key, label], k) => {
        const b = el("button", "sc-layer", label); b.dataset.layer = key;
        b.onclick = () => this.setLayer(v, k); bar.append(b); v.buttons.push(b);
      });
      root.append(canvas, bar, scale);
      this.events(v); this.views.push(v);
      return v;
    }

    // the three.js objects of a payload, built on its first draw and shared by the views showing it
    shape(v) {
      const key = v.script.dataset.view;
      if (this.shapes.has(key)) return this.shapes.get(key);
      const T = this.T, d = JSON.parse(v.script.textContent);
      const q = typed(d.positions, Uint16Array), pos = new Float32Array(q.length);
      for (let i = 0; i < q.length; i++) pos[i] = d.lo[i % 3] + d.step[i % 3] * q[i];
      const g = new T.BufferGeometry();
      g.setAttribute("position", new T.BufferAttribute(pos, 3));
      const rgb = new T.BufferAttribute(new Uint8Array(d.n * 3), 3, true);
      g.setAttribute("rgb", rgb);
      const faces = typed(d.faces, d.index === "uint32" ? Uint32Array : Uint16Array);
      if (faces) g.setIndex(new T.BufferAttribute(faces, 1));
      g.computeBoundingSphere(); g.computeBoundingBox();
      const mat = this.material(!!faces, d.shading);
      const object = faces ? new T.Mesh(g, mat) : new T.Points(g, mat);
      const s = { d, g, object, rgb, shown: -1, centre: g.boundingSphere.center.clone(),
        radius: g.boundingSphere.radius || 1,
        layers: [typed(d.transfer, Uint8Array), typed(d.doubt, Uint8Array)] };
      this.shapes.set(key, s);
      return s;
    }

    // one material per kind (mesh, points) and shading, shared by the views
    material(faces, shading) {
      const key = `${faces} ${shading}`;
      if (!this.materials.has(key)) {
        this.materials.set(key, material(this.T, faces, shading, 3 * (window.devicePixelRatio || 1)));
      }
      return this.materials.get(key);
    }

    setLayer(v, k) { v.layer = k; this.draw(v); }

    showScale(v, s) {
      v.buttons.forEach((b, i) => { b.classList.toggle("sc-on", i === v.layer); b.disabled = !s.layers[i]; });
      const c = s.d.doubt_scale;
      v.scale.innerHTML = "";
      if (v.layer !== 1 || !c) return;
      const ramp = el("div", "sc-ramp");
      ramp.style.background = `linear-gradient(to right, ${c.stops.join(", ")})`;
      const ticks = el("div", "sc-ticks");
      ticks.append(el("span", "", fmt(c.lo)), el("span", "", fmt(c.hi)));
      v.scale.append(ramp, ticks); v.scale.title = c.label;
    }

    draw(v) {
      const T = this.T, s = this.shape(v), c = v.canvas;
      if (!s.layers[v.layer]) v.layer = 0;
      if (s.shown !== v.layer) { s.rgb.array.set(s.layers[v.layer]); s.rgb.needsUpdate = true; s.shown = v.layer; }
      if (v.elev === undefined) [v.elev, v.azim] = s.d.view;
      const ratio = window.devicePixelRatio || 1, w = c.clientWidth || 160, h = c.clientHeight || 120;
      if (c.width !== Math.round(w * ratio)) { c.width = Math.round(w * ratio); c.height = Math.round(h * ratio); }
      this.renderer.setPixelRatio(ratio); this.renderer.setSize(w, h, false);
      const f = viewFrame(T, v.elev, v.azim);
      if (!v.fitted) v.fitted = fitBox(s.g.boundingBox, s.centre, f);
      aim(this.camera, s.centre, s.radius, f, v.fitted, w / h, v.zoom);
      this.mark.visible = !!s.d.suggest;
      if (s.d.suggest) { this.mark.position.set(...s.d.suggest); this.mark.scale.setScalar(s.radius * 0.045); }
      this.scene.add(s.object);
      this.renderer.render(this.scene, this.camera);
      this.scene.remove(s.object);
      const ctx = c.getContext("2d");
      ctx.clearRect(0, 0, c.width, c.height);
      ctx.drawImage(this.renderer.domElement, 0, 0, c.width, c.height);
      v.frames += 1; this.frames += 1;
      this.showScale(v, s);
    }

    events(v) {
      const c = v.canvas;
      let drag = null, pending = false;
      c.addEventListener("pointerdown", (e) => { drag = [e.clientX, e.clientY]; c.setPointerCapture(e.pointerId); });
      c.addEventListener("pointerup", (e) => { drag = null; c.releasePointerCapture(e.pointerId); });
      c.addEventListener("pointermove", (e) => {
        if (!drag) return;
        v.azim -= (e.clientX - drag[0]) * 0.8;
        v.elev = Math.max(-90, Math.min(90, v.elev + (e.clientY - drag[1]) * 0.8));
        drag = [e.clientX, e.clientY];
        if (!pending) { pending = true; requestAnimationFrame(() => { pending = false; this.draw(v); }); }
      });
      c.addEventListener("dblclick", () => { v.elev = undefined; v.fitted = null; this.draw(v); });
    }
  }

  async function start() {
    const api = window.shapecond;
    try {
      const src = document.getElementById("sc-three").textContent;
      const T = await import(URL.createObjectURL(new Blob([src], { type: "text/javascript" })));
      document.querySelectorAll(".sc-viewer").forEach((root) => {
        const data = JSON.parse(root.querySelector("script.sc-data").textContent);
        api.viewers.push(new Viewer(T, root, data));
      });
      if (document.querySelector(".sc-mapview")) api.mapviews = new MapViews(T);
      api.ready = true;
    } catch (err) {
      api.error = String(err);
      console.error("shapecond viewer: " + err);
      document.querySelectorAll(".sc-viewer, .sc-mapview").forEach((r) => r.append(el("p", "sc-error",
        "The 3D view could not start (" + err + "); a browser with WebGL 2 is needed.")));
    }
  }
  window.shapecond = { viewers: [], mapviews: null, ready: false, error: null };
  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start); else start();
})();
