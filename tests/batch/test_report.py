"""``report.html`` of a matched batch, from rows alone (no matching)."""

from shapecond.batch import schema
from shapecond.batch.report import collection_landmark, report_html


def _row(name, bar, **extra):
    row = schema.empty_row()
    row.update(file=f"/c/{name}.off", match_template="/c/t.off", match_direction="template to shape",
               match_source="/c/t.off", match_target=f"/c/{name}.off", bar=bar, bar_epsilon=0.01,
               bar_epsilon_hat=0.01, landmark_pairs=6, landmark_labels="a b c d e f", map_file=f"/c/maps/{name}.txt",
               seconds=1.0, **extra)
    return row


def test_the_annotate_more_list_puts_the_largest_bar_first_and_every_map_is_listed_best_first():
    rows = [_row("mid", 0.2), _row("fine", 0.01), _row("worst", 0.4), _row("bad", 0.06),
            _row("broken", None, error="no landmarks for this shape")]
    page = report_html(rows)
    more, every = page.split("<h2>Annotate more</h2>")[1].split("<h2>Every map, by its bar</h2>")
    order = [more.index(f"t → {n}<") for n in ("worst", "mid", "bad")]
    assert order == sorted(order) and "t → fine<" not in more
    order = [every.index(f"t → {n}<") for n in ("fine", "bad", "mid", "worst")]
    assert order == sorted(order)
    assert "3 of them say <b>annotate more</b>, 1 failed" in page and "no landmarks for this shape" in every


def test_the_template_vertex_most_often_suggested_is_one_landmark_for_the_collection():
    rows = [_row("a", 0.3, suggest_source_id=41), _row("b", 0.2, suggest_source_id=41),
            _row("c", 0.1, suggest_source_id=7), _row("fine", 0.01, suggest_source_id=7),
            _row("back", 0.4, suggest_source_id=7)]
    rows[-1]["match_direction"] = "shape to template"
    page = report_html(rows)
    assert "template vertex 41 is the next landmark of 2 of the 3 maps listed" in page  # "fine": not listed,
    assert collection_landmark(rows) == {"template_vertex": 41, "maps": 2, "listed": 3}
    rows[1]["suggest_source_id"] = 8                                                    # "back": a shape's id
    assert "One landmark for the collection" not in report_html(rows)  # no vertex shared by two maps
    assert collection_landmark(rows) is None


def _fake_view(size: int) -> dict:
    """A stand-in view payload of about ``size`` bytes (the report reads only its size)."""
    return {"format": 1, "n": 1, "pad": "x" * size}


def test_views_beyond_the_budget_keep_the_annotate_more_list_then_the_largest_bars(monkeypatch):
    from shapecond.batch import report

    bars = [0.01, 0.02, 0.03, 0.04, 0.06, 0.07, 0.5]
    rows = [_row(f"s{k}", b) for k, b in enumerate(bars)]
    views = {r["map_file"]: _fake_view(1000) for r in rows}
    views[rows[1]["map_file"]] = None  # a map without its view (a batch from before views)
    page = report_html(rows, views)
    assert page.count("<div class=\"sc-mapview\"") == 6 + 3 and "views left out" not in page
    monkeypatch.setattr(report, "MAX_VIEW_BYTES", 4500)  # four views fit
    page = report_html(rows, views)
    every = page.split("<h2>Every map, by its bar</h2>")[1]
    shown = [n for n in range(7) if f't → s{n}</td><td><div class="sc-mapview"' in every]
    assert shown == [3, 4, 5, 6]  # the three that say annotate more, then the largest other bar
    assert "<b>2 views left out</b>" in page


def test_a_view_is_read_only_for_the_row_it_was_written_for(tmp_path):
    import os

    from shapecond.batch.matches import read_view, view_path, write_view

    row = _row("cat", 0.02, content_hash="abc", params='{"pairs":[]}')
    row["map_file"] = str(tmp_path / "maps" / "cat.txt")
    assert view_path(row["map_file"]) == tmp_path / "views" / "cat.json"
    assert read_view(row) is None  # none written
    write_view(view_path(row["map_file"]), _fake_view(10), row)
    assert read_view(row)["pad"] == "x" * 10
    assert read_view({**row, "params": '{"pairs":[["a","a"]]}'}) is None  # other landmarks since
    assert read_view({**row, "content_hash": "abd"}) is None              # another shape
    view_path(row["map_file"]).write_text("{not json")
    assert read_view(row) is None
    view_path(row["map_file"]).unlink()
    os.mkfifo(view_path(row["map_file"]))  # refused without blocking
    assert read_view(row) is None
