"""``report.html`` of a matched batch, from rows alone (no matching)."""

from shapecond.batch import schema
from shapecond.batch.report import report_html


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
