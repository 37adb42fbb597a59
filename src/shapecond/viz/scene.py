"""Render data: what a picture shows, computed once for the PNG, the PLY and the HTML viewer.

A :class:`Scene` is one shape in display coordinates (centred, its vertical axis
turned to z, see ``display_frame``) with one or more :class:`Layer` colourings:
per-vertex RGBA colours, the values behind them (for a colour bar and for the
HTML viewer's hover read-out), landmarks in order with their marker colours and
labels, and segments (the witness map's moves).  ``render.render_scene`` draws a
Scene with matplotlib; ``html.scene_html`` embeds the same Scene in a page.
Colours, views, landmark styles, labels and shading constants are defined here
only, so the two kinds of picture cannot drift apart.

The builders ``heatmap_scene``, ``witness_scene`` and ``landmark_scene`` compute the
scenes of ``shapecond heatmap``, ``score --witness-png`` and ``landmarks``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import matplotlib
import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError
from ..symmetry.starts import classical_mds

#: Default views as (elevation, azimuth) in degrees around the up axis: three-quarter
#: front, both sides (a mirror ambiguity shows up as a left/right difference) and top.
DEFAULT_VIEWS = ((20.0, -60.0), (5.0, 0.0), (5.0, 180.0), (80.0, 0.0))
#: Headlight shading of a face: ``AMBIENT + DIFFUSE |n·v|`` (n the face normal, v the view direction).
AMBIENT, DIFFUSE = 0.35, 0.65
#: Landmark markers (paper Figure 6): the first three red, the rest green; RGB in [0, 1].
LANDMARK_FIRST, LANDMARK_REST = (230 / 255, 20 / 255, 20 / 255), (30 / 255, 200 / 255, 30 / 255)
#: Colour of a vertex without values.
GREY = (0.75, 0.75, 0.75)
#: A landmark is drawn as facing the viewer while ``normal · toward > FACING`` (hollow marker otherwise).
FACING = -0.2

_AXES = {"x": 0, "y": 1, "z": 2}


def view_label(elev: float, azim: float) -> str:
    """Caption of a view (PNG panel title, HTML button)."""
    return f"elev {elev:g}°, azim {azim:g}°"


def landmark_colour(i: int) -> tuple:
    """RGB of the ``i``-th landmark (0-based): red for the first three, green after."""
    return LANDMARK_FIRST if i < 3 else LANDMARK_REST


@dataclass(frozen=True)
class ColourBar:
    """A scalar colour scale: ``cmap`` from ``lo`` to ``hi``, with its caption."""

    cmap: str
    lo: float
    hi: float
    label: str | None = None

    def mappable(self):
        """matplotlib ScalarMappable of this scale (the one colour mapping of shapecond)."""
        norm = matplotlib.colors.Normalize(self.lo, self.hi)
        return matplotlib.cm.ScalarMappable(norm=norm, cmap=self.cmap)

    def stops(self, k: int = 33) -> list:
        """``k`` colours evenly spaced from ``lo`` to ``hi`` as ``#rrggbb`` (for a CSS gradient)."""
        rgba = self.mappable().to_rgba(np.linspace(self.lo, self.hi, k))
        return [matplotlib.colors.to_hex(c) for c in rgba]


@dataclass(frozen=True)
class Colouring:
    """How scalars become colours (``colour_layer``): ``cmap`` from ``vmin`` to ``vmax`` (None: the finite
    range of the values), ``label`` the colour bar's caption."""

    cmap: str = "viridis"
    vmin: float | None = None
    vmax: float | None = None
    label: str | None = None


@dataclass(frozen=True)
class Place:
    """How a scene stands and what it says (``make_scene``).

    Attributes
    ----------
    up : the data's vertical direction ("z", "y", a signed "-y"...); None: the vertices are display
        coordinates already (kept as they are).  The scenes of one shape (``heatmap_scene``,
        ``witness_scene``, ``landmark_scene``'s callers) read None as "guess it" (``guess_up``).
    views : (elevation, azimuth) camera positions in degrees.
    title : the scene's title.
    notes : texts shown with the scene.
    point_size : marker size of a point cloud; None: 6, or 30 for a point cloud of at most 2000 points.
    """

    up: str | None = "z"
    views: tuple = DEFAULT_VIEWS
    title: str | None = None
    notes: tuple = ()
    point_size: float | None = None


@dataclass(frozen=True, eq=False)
class Layer:
    """One colouring of a scene's vertices.

    Attributes
    ----------
    rgba : (n, 4) float array in [0, 1]
    label : caption of the layer (a PNG row's caption, an HTML button)
    values : (n,) per-vertex values read out on hover, or None
    value_name : what ``values`` are
    colorbar : ColourBar or None (direct colours)
    landmarks : vertex indices of the scene, in order (markers numbered from 1)
    notes : one text per landmark (e.g. its score), or empty
    segments : (k, 2, 3) display coordinates of moves drawn as chords, or None
    ranks : place of each landmark in its order (colour and number), default 0, 1, 2, ...
        (two shapes side by side list the same ranks twice)
    """

    rgba: np.ndarray
    label: str | None = None
    values: np.ndarray | None = None
    value_name: str | None = None
    colorbar: ColourBar | None = None
    landmarks: tuple = ()
    notes: tuple = ()
    segments: np.ndarray | None = None
    ranks: tuple = ()

    def rank(self, i: int) -> int:
        """Place in the landmark order of the ``i``-th marker (0-based)."""
        return int(self.ranks[i]) if self.ranks else i


@dataclass(frozen=True, eq=False)
class Scene:
    """One shape (or several side by side) in display coordinates with its layers.

    Attributes
    ----------
    vertices : (n, 3) display coordinates (``(x - centre) @ frame.T``: centred, up = z)
    faces : (m, 3) int array or None (a point cloud)
    layers : tuple of Layer
    ids : (n,) the id shown for each vertex (the input's vertex ids)
    views : (elevation, azimuth) pairs in degrees (``render.view_rotation``)
    title : str or None
    centre, frame : the map from input to display coordinates
    point_size : marker size of a point cloud in the PNG
    parts : ((name, start, stop), ...) vertex ranges of several shapes; empty for one
    partner : (n,) vertex index each vertex is linked to (-1: none), or None
    normals : (n, 3) unit vertex normals (meshes) or None
    notes : lines printed with the picture
    suggestions : ((vertex index, label), ...) points drawn with their own markers (HTML only)
    picking : None, or the pieces of the command a page builds from landmark pairs picked by clicking a
        vertex of the first part, then one of the second (HTML only; ``viz.pages.match_page``)
    """

    vertices: np.ndarray
    faces: np.ndarray | None
    layers: tuple
    ids: np.ndarray
    views: tuple = DEFAULT_VIEWS
    title: str | None = None
    centre: np.ndarray = field(default_factory=lambda: np.zeros(3))
    frame: np.ndarray = field(default_factory=lambda: np.eye(3))
    point_size: float = 6.0
    parts: tuple = ()
    partner: np.ndarray | None = None
    normals: np.ndarray | None = None
    notes: tuple = ()
    suggestions: tuple = ()
    picking: dict | None = None

    @property
    def n_vertices(self) -> int:
        return int(self.vertices.shape[0])

    def to_display(self, points) -> np.ndarray:
        """Input coordinates (k, 3) to display coordinates."""
        return (np.asarray(points, dtype=float) - self.centre) @ self.frame.T

    def with_layers(self, layers) -> "Scene":
        return replace(self, layers=tuple(layers))


def _axis(up: str) -> np.ndarray:
    """Unit vector of an up direction: ``"x"``, ``"y"``, ``"z"``, optionally signed (``"-y"``, ``"+z"``)."""
    if up not in {sign + axis for sign in ("", "+", "-") for axis in _AXES}:
        raise InputError(f"up axis must be one of x, y, z (optionally signed: -y), got {up!r}")
    return np.eye(3)[_AXES[up[-1]]] * (-1.0 if up.startswith("-") else 1.0)


def up_frame(up: str, V: np.ndarray | None = None) -> np.ndarray:
    """Rotation taking the data's ``up`` direction (an axis, optionally signed: ``"-y"``) to z (rows: new
    x, y, z axes).

    Of the two horizontal axes, the one along which the shape is longer becomes the
    new y, so that azimuth 0 and 180 look at the shape's broad sides (an animal's
    flanks, a standing human's front and back) whatever the file's convention.
    """
    z = _axis(up)
    k = int(np.argmax(np.abs(z)))
    a, b = np.eye(3)[(k + 1) % 3], np.eye(3)[(k + 2) % 3]
    if V is not None and np.ptp(V @ a) > np.ptp(V @ b):
        a, b = b, a
    y = b
    x = np.cross(y, z)
    return np.stack([x, y, z])


#: ``guess_up``: the extremities looked at (geodesic farthest points), how close to a floor one must be
#: (fraction of the shape's extent along the direction, at least ``UP_MIN_EXTENT`` of its largest extent),
#: the smallest extent of an up direction (fraction of the largest) and the default's head start.
UP_EXTREMITIES, UP_FLOOR, UP_MIN_EXTENT, UP_PRIOR = 8, 0.03, 0.3, 1.0
#: The directions ``guess_up`` chooses among (x is the horizontal "right" of every common convention).
UP_CANDIDATES = ("z", "-z", "y", "-y")


def extremities(V: np.ndarray, F: np.ndarray | None, m: int = UP_EXTREMITIES) -> np.ndarray:
    """The first ``m`` farthest-point samples under the edge-graph geodesic distance (internal indices).

    The first is the vertex farthest from the one nearest the centroid; each next one
    is farthest from those so far: on a body they are the tips of its limbs, head and
    tail.  A point cloud is joined to its 6 nearest neighbours.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    n = V.shape[0]
    if F is not None and len(F):
        E = np.vstack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    else:
        _, nn = cKDTree(V).query(V, k=min(7, n))
        E = np.column_stack([np.repeat(np.arange(n), nn.shape[1] - 1), nn[:, 1:].ravel()])
    w = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1) + 1e-12
    G = coo_matrix((w, (E[:, 0], E[:, 1])), shape=(n, n)).tocsr()

    def row(i):
        d = dijkstra(G, directed=False, indices=int(i))
        return np.where(np.isfinite(d), d, -1.0)  # another component: never chosen

    far = row(np.argmin(np.linalg.norm(V - V.mean(axis=0), axis=1)))
    picks = [int(np.argmax(far))]
    front = row(picks[0])
    while len(picks) < min(m, n):
        picks.append(int(np.argmax(front)))
        front = np.minimum(front, row(picks[-1]))
    return np.asarray(picks, dtype=np.int64)


def floor_scores(vertices, faces=None) -> dict:
    """Per candidate up direction (``UP_CANDIDATES``): how many extremities rest on the floor below.

    A direction's floor is the plane through the shape's lowest vertex along it;
    an extremity rests on it when it lies within ``UP_FLOOR`` of the shape's extent
    along the direction (at least ``UP_MIN_EXTENT`` of the largest extent).  The
    score is that count plus a tie-break in [0, 1): one minus the mean height of all
    the extremities.  A direction along which the shape is flatter than
    ``UP_MIN_EXTENT`` of its largest extent scores -inf.
    """
    V = np.asarray(vertices, dtype=float)
    F = None if faces is None else np.asarray(faces, dtype=np.int64)
    X = extremities(V, F)
    top = float(np.ptp(V, axis=0).max()) or 1.0
    out = {}
    for up in UP_CANDIDATES:
        h = V @ _axis(up)
        ext = float(np.ptp(h))
        if ext < UP_MIN_EXTENT * top:
            out[up] = -np.inf
            continue
        rel = (h[X] - h.min()) / max(ext, UP_MIN_EXTENT * top)
        out[up] = float(np.count_nonzero(rel <= UP_FLOOR)) + 1.0 - float(np.clip(rel.mean(), 0.0, 1.0)) * 0.999
    return out


def guess_up(*geometries) -> str:
    """Up direction of one or more shapes drawn together: ``"z"``, ``"y"`` or a signed ``"-y"``, ``"-z"``.

    A standing body rests on its feet: the up direction is the one whose floor most
    of the body's extremities (the tips of legs, arms, head and tail, found as the
    first geodesic farthest points, ``extremities``) touch — two feet, four paws —
    where a head, a nose or a hand stands alone at the other ends.  The shape's
    extents cannot decide it (a standing human is tallest along its up axis, a
    four-legged animal longest along its body), and the file format does not say it.

    The candidates are ±z and ±y (x is the horizontal "right" of the common
    conventions: TOSCA's z-up, OBJ/PLY's y-up, SMAL releases' -y-up); ``"z"`` has a
    head start of ``UP_PRIOR``: another direction wins when two more extremities touch
    its floor than z's, or one more and the tie-break (their mean height) favours it
    (``floor_scores``).  The scores of several shapes add up (both shapes of a match
    page stand alike).  Unusual poses can fool it (a body lying, sitting, jumping):
    pass ``up`` explicitly there.  Without a surface (a distance matrix, None): ``"z"``.
    """
    total = {up: UP_PRIOR if up == "z" else 0.0 for up in UP_CANDIDATES}
    for g in geometries:
        V = getattr(g, "vertices", None)
        if V is None or len(V) < 4:
            continue
        for up, s in floor_scores(V, getattr(g, "faces", None)).items():
            total[up] += s
    return max(UP_CANDIDATES, key=lambda up: total[up])  # ties: the earlier candidate


def colour_layer(data, n: int, colouring: Colouring = Colouring(), *, hover=None) -> Layer:
    """A Layer coloured by ``data``: None (grey), (n,) scalars through ``colouring`` or (n, 3|4) colours.

    Scalars get a ColourBar from ``colouring`` (default range: their finite range; non-finite values
    take the top colour).  ``hover``: the values read out on hover (default: the scalars themselves).
    The Layer's other fields (``label``, ``landmarks``, ``value_name``, ...) are set by the caller
    (``dataclasses.replace``).
    """
    values = None if hover is None else np.asarray(hover, dtype=float)
    if data is None:
        return Layer(np.tile([*GREY, 1.0], (n, 1)), values=values)
    v = np.asarray(data, dtype=float)
    if v.ndim == 2 and v.shape[0] == n and v.shape[1] in (3, 4):
        rgba = np.ones((n, 4))
        rgba[:, : v.shape[1]] = np.clip(v, 0.0, 1.0)
        return Layer(rgba, values=values)
    if v.shape != (n,):
        raise InputError(f"values must have shape ({n},), ({n}, 3) or ({n}, 4), got {v.shape}")
    finite = v[np.isfinite(v)]
    vmin, vmax = colouring.vmin, colouring.vmax
    lo = float(np.min(finite)) if vmin is None and finite.size else (vmin if vmin is not None else 0.0)
    hi = float(np.max(finite)) if vmax is None and finite.size else (vmax if vmax is not None else 1.0)
    if hi <= lo:
        hi = lo + 1.0
    bar = ColourBar(colouring.cmap, float(lo), float(hi), colouring.label)
    rgba = np.asarray(bar.mappable().to_rgba(np.where(np.isfinite(v), v, hi)), dtype=float)
    return Layer(rgba, values=v if values is None else values, colorbar=bar)


def layer_of(spec: dict, n: int) -> Layer:
    """The Layer of a dict of ``make_scene``: ``values`` coloured by ``cmap``, ``vmin``, ``vmax`` and
    ``colorbar_label`` (``Colouring``), the other keys the Layer's fields (``label``, ``landmarks``,
    ``notes``, ...)."""
    spec = dict(spec)
    colouring = Colouring(spec.pop("cmap", "viridis"), spec.pop("vmin", None), spec.pop("vmax", None),
                          spec.pop("colorbar_label", None))
    return replace(colour_layer(spec.pop("values", None), n, colouring), **spec)


def make_scene(vertices, faces, layers, *, ids=None, place: Place = Place()) -> Scene:
    """A Scene of one shape given in input coordinates (checked; landmarks must be vertex indices).

    ``layers`` are Layers, or dicts of ``layer_of`` (``values``, ``cmap``, ``vmin``, ``vmax``,
    ``colorbar_label``, ``label``, ``landmarks``, ``notes``, ``segments`` in input coordinates).
    ``ids``: the input's id of every vertex (default: their indices).  ``place``: up direction
    (None: ``vertices`` are display coordinates already), views, title, notes and point size.
    """
    from ..deformation.energy import vertex_normals

    V = np.asarray(vertices, dtype=float)
    if V.ndim != 2 or V.shape[1] != 3 or V.shape[0] == 0:
        raise InputError("vertices must be a non-empty (n, 3) array")
    n = V.shape[0]
    F = None if faces is None else np.asarray(faces, dtype=np.int64)
    if F is not None and (F.ndim != 2 or F.shape[1] != 3 or (F.size and (F.min() < 0 or F.max() >= n))):
        raise InputError("faces must be an (m, 3) array of vertex indices")
    if not place.views:
        raise InputError("at least one view is needed")
    up = place.up
    centre, frame = (np.zeros(3), np.eye(3)) if up is None else (V.mean(axis=0), up_frame(up, V))
    D = (V - centre) @ frame.T
    out = []
    for lay in layers:
        if isinstance(lay, dict):
            seg = lay.get("segments")
            lay = layer_of({k: v for k, v in lay.items() if k != "segments"}, n)
            if seg is not None:
                seg = np.asarray(seg, dtype=float).reshape(-1, 2, 3)
                lay = replace(lay, segments=(seg - centre) @ frame.T)
        lms = tuple(int(v) for v in lay.landmarks)
        if any(v < 0 or v >= n for v in lms):
            raise InputError("landmark vertex index out of range")
        out.append(replace(lay, landmarks=lms))
    point_size = place.point_size
    if point_size is None:
        point_size = 6.0 if F is not None or n > 2000 else 30.0
    return Scene(D, F, tuple(out), np.arange(n) if ids is None else np.asarray(ids, dtype=np.int64),
                 tuple(tuple(float(a) for a in v) for v in place.views), centre=centre, frame=frame,
                 point_size=float(point_size), normals=None if F is None else vertex_normals(D, F),
                 title=place.title, notes=tuple(place.notes))


# --- the scenes of the commands ----------------------------------------------------------

def shape_points(shape):
    """(vertices, faces, vertex of each point of Y, ids) of a MetricShape; classical MDS for a matrix."""
    geom = getattr(shape, "geometry", None)
    if geom is not None and getattr(shape, "samples", None) is not None:
        V = np.asarray(geom.vertices, float)
        ids = getattr(geom, "ids", None)  # a stand-in without ids: the row indices
        return (V, geom.faces, np.asarray(shape.samples, np.int64),
                np.arange(len(V)) if ids is None else np.asarray(ids, np.int64))
    V = classical_mds(np.asarray(shape.D, float))
    return V, None, np.arange(V.shape[0]), np.arange(V.shape[0])


def idw(V: np.ndarray, sources, values, k: int = 4) -> np.ndarray:
    """Inverse-distance weighting of ``values`` at vertices ``sources`` over the ``k`` Euclidean-nearest
    of them, weights ``1 / (d + ε)²`` (the ``"smooth"`` interpolation); every value must be finite."""
    src = np.asarray(sources, dtype=np.int64)
    vals = np.asarray(values, dtype=float)
    kk = min(k, src.size)
    d, idx = cKDTree(V[src]).query(V, k=kk)
    if kk == 1:
        d, idx = d[:, None], idx[:, None]
    eps = 1e-9 + 1e-3 * np.median(d[:, -1])
    w = 1.0 / (d + eps) ** 2
    return (w * vals[idx]).sum(axis=1) / w.sum(axis=1)


def interpolate_to_vertices(shape, values, method: str = "smooth", k: int = 4) -> np.ndarray:
    """Spread per-sample ``values`` ((N,) over X or (M,) over Y) to every vertex.

    Returns an (n_vertices,) array (for a matrix input: one value per point of Y).
    Non-finite values (σ = ∞) are kept as ``inf`` by ``"nearest"``; ``"smooth"``
    treats them as the largest finite value so the colour scale stays usable.
    """
    values = np.asarray(values, dtype=float)
    n, m = int(shape.n_samples), int(np.asarray(shape.D).shape[0])
    if values.shape not in ((n,), (m,)):
        raise InputError(f"values must have {n} (samples) or {m} (targets) entries, got {values.shape}")
    V, _, pts, _ = shape_points(shape)
    src = pts[: values.size]
    if method == "nearest":
        near = getattr(shape, "nearest", None)
        if values.size == m and near is not None and getattr(shape, "geometry", None) is not None:
            return values[np.asarray(near)]
        _, idx = cKDTree(V[src]).query(V)
        return values[idx]
    if method != "smooth":
        raise InputError(f"unknown interpolation {method!r} (nearest or smooth)")
    vals = values.copy()
    finite = np.isfinite(vals)
    if not finite.any():
        return np.full(V.shape[0], np.inf)
    vals[~finite] = vals[finite].max()
    return idw(V, src, vals, k)


@dataclass(frozen=True)
class HeatMapStyle:
    """How a heat map is drawn (``heatmap_scene``, ``viz.heatmap.render_heatmap_png``).

    Attributes
    ----------
    up : the data's vertical direction; None guesses it (``guess_up``).
    views, title : as ``Place``.
    method : "smooth" or "nearest" interpolation between the samples (``interpolate_to_vertices``).
    cmap, colorbar_label : the colour map and the colour bar's caption.
    log : colour by log10 of the values; None: when max/min > 20 (points near a mirror plane keep
        huge scores and would flatten the rest of the scale).  Infinite values are drawn with the
        largest finite one.
    """

    up: str | None = None
    views: tuple = DEFAULT_VIEWS
    title: str | None = None
    method: str = "smooth"
    cmap: str = "turbo"
    colorbar_label: str = "σ with the point fixed"
    log: bool | None = None


def heatmap_scene(shape, values, *, landmarks=(), style: HeatMapStyle = HeatMapStyle()) -> Scene:
    """The heat map of ``viz.heatmap.render_heatmap_png`` as a Scene (see there for the arguments)."""
    V, F, pts, ids = shape_points(shape)
    vv = interpolate_to_vertices(shape, values, method=style.method)
    finite = vv[np.isfinite(vv)]
    vmax = float(finite.max()) if finite.size else 1.0
    vv = np.where(np.isfinite(vv), vv, vmax)
    log = style.log
    if log is None:  # auto: a wide range (one near-symmetry left) would flatten everything else
        log = finite.size > 0 and finite.min() > 0 and vmax / finite.min() > 20.0
    shown = np.log10(vv) if log else vv
    label = f"log10 {style.colorbar_label}" if log else style.colorbar_label
    lm = [int(pts[int(i)]) for i in landmarks]
    layer = replace(colour_layer(shown, len(V), Colouring(style.cmap, label=label), hover=vv), landmarks=lm,
                    value_name=style.colorbar_label)
    up = style.up or guess_up(getattr(shape, "geometry", None))
    return make_scene(V, F, [layer], ids=ids, place=Place(up, style.views, style.title))


def position_colours(V: np.ndarray) -> np.ndarray:
    """RGB in [0.1, 0.95] from coordinates normalised to the bounding box."""
    lo, hi = V.min(axis=0), V.max(axis=0)
    c = (V - lo) / np.where(hi > lo, hi - lo, 1.0)
    return 0.1 + 0.85 * c


def witness_scene(shape, witness, *, landmarks=(), place: Place = Place(up=None), max_segments: int = 80) -> Scene:
    """The two rows of ``viz.witness.render_witness_png`` (reference colours, their pull-back) as a Scene;
    ``place.up`` None guesses the up direction (``guess_up``)."""

    D = np.asarray(shape.D, dtype=float)
    n = int(shape.n_samples)
    t = np.asarray(witness, dtype=np.int64)
    if t.shape != (n,) or t.min() < 0 or t.max() >= D.shape[0]:
        raise InputError(f"witness must be {n} indices into range({D.shape[0]})")
    V, F, pts, ids = shape_points(shape)
    ref = position_colours(V)
    _, near = cKDTree(V[pts[:n]]).query(V)  # every vertex -> nearest sample of X (colouring only)
    disp = D[np.arange(n), t]
    order = np.argsort(-disp, kind="stable")[:max_segments]
    order = order[disp[order] > 0]
    segments = np.stack([V[pts[order]], V[pts[t[order]]]], axis=1)
    lm = [int(pts[int(i)]) for i in landmarks]
    moved = int(np.count_nonzero(disp > 0))
    target_id = ids[pts[t[near]]]
    layers = [dict(values=ref, landmarks=lm, label="reference (colour = position)"),
              dict(values=ref[pts[t[near]]], landmarks=lm, segments=segments,
                   label=f"witness T ({moved}/{n} samples moved)")]
    scene = make_scene(V, F, layers, ids=ids,
                       place=replace(place, up=place.up or guess_up(getattr(shape, "geometry", None))))
    # hover read-out of the witness layer: where the nearest sample is sent (input id)
    wit = replace(scene.layers[1], values=target_id.astype(float), value_name="nearest sample sent to vertex")
    return scene.with_layers([scene.layers[0], wit])


def landmark_scene(V, F, landmarks, *, notes=(), label="landmarks", ids=None, place: Place = Place()) -> Scene:
    """A grey shape with landmarks in order; ``notes``: one text per landmark (e.g. the score after it);
    ``ids`` and ``place`` as ``make_scene``."""
    return make_scene(V, F, [dict(landmarks=landmarks, notes=tuple(notes), label=label)], ids=ids, place=place)
