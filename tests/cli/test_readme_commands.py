"""The README's commands work as written: the set-up commands' entry point and test extra, and
every sub-command, option and option value of the command table and of the shared shape options."""

import re
from importlib import metadata
from pathlib import Path

import pytest

from tests.helpers import run_cli

README = (Path(__file__).resolve().parents[2] / "README.md").read_text()
SECTION = README[README.index("## Command line"):]
SECTION = SECTION[:SECTION.index("\n## ", 1)]
OPTION = re.compile(r"^--?[a-zA-Z][\w-]*$")


def _table():
    """(command, [(option, value spec or None)]) for every row `shapecond ...` of the command table."""
    rows = []
    for spec in re.findall(r"^\| `shapecond ([^`]*)` \|", SECTION, re.M):
        tokens = [t.strip("[]") for t in spec.replace("\\|", "|").split()]
        options = []
        for k, tok in enumerate(tokens):
            if OPTION.match(tok):
                nxt = tokens[k + 1] if k + 1 < len(tokens) else ""
                options.append((tok, None if not nxt or OPTION.match(nxt) or nxt == "|" else nxt))
        rows.append((tokens[0], tokens[1] if tokens[0] == "cache" else None, options))
    return rows


TABLE = _table()


def _shared_options():
    """The commands and options of the paragraph 'Shape options shared by ...'."""
    head, body = re.search(r"Shape options shared by (.*?):(.*?)\n\n", SECTION, re.S).groups()
    return re.findall(r"`(\w+)`", head), re.findall(r"`(--[\w-]+)", body)


def _help_options(help_text):
    """{option: metavar or None} from a click help page (``-n, --points INTEGER``, ``--force``)."""
    out = {}
    for names, metavar in re.findall(r"^  ((?:--?[\w-]+(?:, | / )?)+)(?: (\S+))?(?: {2,}|$)", help_text, re.M):
        for name in re.split(r", | / ", names.strip()):
            out[name] = metavar or None
    return out


def test_the_set_up_commands_install_the_shapecond_command_and_the_test_extra():
    setup = re.search(r"```bash\n(.*?)```", README, re.S).group(1)
    assert ".venv/bin/shapecond demo" in setup and "pip install '.[test]'" in setup and "-m pytest" in setup
    scripts = [e for e in metadata.entry_points(group="console_scripts") if e.name == "shapecond"]
    assert len(scripts) == 1
    from shapecond.cli import main

    assert scripts[0].load() is main
    assert "test" in (metadata.metadata("shapecond").get_all("Provides-Extra") or [])
    extra = [r for r in metadata.requires("shapecond") or [] if re.search(r"""extra\s*==\s*["']test["']""", r)]
    assert any(re.match(r"pytest\b", r) for r in extra), extra


def test_the_test_command_runs_in_workers_that_the_test_extra_installs():
    """``pytest -n 2`` needs pytest-xdist: the test extra of pyproject.toml (read from the file, as
    a fresh ``pip install '.[test]'`` reads it) lists it, and ``.ci/run`` runs the README's command."""
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11

    setup = re.search(r"```bash\n(.*?)```", README, re.S).group(1)
    command = re.search(r"-m pytest[^\n]*", setup).group(0)
    assert " -n 2" in command, command
    root = Path(__file__).resolve().parents[2]
    extra = tomllib.loads((root / "pyproject.toml").read_text())["project"]["optional-dependencies"]["test"]
    assert any(re.match(r"pytest-xdist\b", r) for r in extra), extra
    assert f"pip install '.[test]' && .venv/bin/python {command}\n" in (root / ".ci" / "run").read_text()


def test_the_table_lists_every_command():
    assert [c for c, _, _ in TABLE] == ["info", "sample", "score", "kappa", "local", "landmarks", "heatmap",
                                        "match", "evaluate", "batch", "demo", "cache"]


@pytest.mark.parametrize("command, sub, options", TABLE, ids=[c for c, _, _ in TABLE])
def test_every_option_of_the_table_parses_with_the_values_it_shows(capsys, command, sub, options):
    subs = sub.split("|") if sub else [None]
    for s in subs:
        argv = [command] + ([s] if s else [])
        code, page, err = run_cli(capsys, *argv, "--help")
        assert code == 0 and page.startswith(f"Usage: shapecond {' '.join(argv)}"), err
        listed = _help_options(page)
        # every option as the README writes it, with a value where it shows one, parses
        given = [a for opt, value in options for a in ([opt] if value is None else [opt, value.split("|")[0]])]
        code, _, err = run_cli(capsys, *argv, *given, "--help")
        assert code == 0, err
        for opt, value in options:
            assert opt in listed, f"{command}: {opt} is not an option"
            assert (value is None) == (listed[opt] is None), f"{command} {opt}: flag or value?"
            choices = listed[opt] or ""
            if value and choices.startswith("[") and "|" in choices:
                words = [v for v in value.split("|") if not v.isupper()]
                assert set(words) <= set(choices.strip("[]").split("|")), (command, opt, words, choices)


def test_the_shared_shape_options_are_options_of_every_command_named(capsys):
    commands, options = _shared_options()
    assert commands == ["sample", "score", "kappa", "landmarks", "heatmap"] and len(options) >= 10
    for command in commands:
        code, page, err = run_cli(capsys, command, "--help")
        assert code == 0, err
        missing = set(options) - set(_help_options(page))
        assert not missing, f"{command} lacks {sorted(missing)}"
