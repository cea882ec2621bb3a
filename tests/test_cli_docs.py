"""What the command line offers is documented beyond ``--help``: every subcommand and every
option in docs/SPEC.md §3, every ``ATLAS_*`` environment variable the package reads in README.md
or docs/; and ``ATLAS_PROGRESS`` does what they say."""

import argparse
import re
from pathlib import Path

import pytest

from atlas.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]
SPEC = (ROOT / "docs" / "SPEC.md").read_text()
CLI_SECTION = SPEC.split("## 3. Interfaces")[1].split("## 4.")[0]


def _subcommands() -> dict[str, list[str]]:
    """Each subcommand and its long options (``--help`` aside)."""
    parser = build_parser("*")
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return {
        name: [o for a in p._actions for o in a.option_strings if o.startswith("--")][1:]
        for name, p in sub.choices.items()
    }


SUBCOMMANDS = _subcommands()


def _bullet(name: str) -> str:
    """The SPEC §3 bullet that lists the options of ``name``."""
    m = re.search(rf"\n  \* `{name}( [A-Za-z.]+)?`: (.*?)(?=\n  \* `|\n\* |\Z)", CLI_SECTION, re.S)
    assert m, f"docs/SPEC.md §3 lists no options of {name}"
    return m.group(2)


def test_spec_names_every_subcommand():
    head = CLI_SECTION.split("* CLI `atlas` with subcommands:")[1].split("\n  * ")[0]
    missing = [name for name in SUBCOMMANDS if f"`{name}`" not in head]
    assert not missing, f"docs/SPEC.md §3 does not name {missing}"


@pytest.mark.parametrize("name", sorted(SUBCOMMANDS))
def test_spec_lists_every_option(name):
    text = _bullet(name)
    missing = [o for o in SUBCOMMANDS[name] if not re.search(rf"`{o}[` ]", text)]
    assert not missing, f"docs/SPEC.md §3, {name}: {missing} only in --help"


def test_every_environment_variable_is_documented():
    read = set()
    for path in (ROOT / "atlas").rglob("*.py"):
        read |= set(re.findall(r"\"(ATLAS_[A-Z_]+)\"", path.read_text()))
    docs = (ROOT / "README.md").read_text() + "".join(
        p.read_text() for p in (ROOT / "docs").glob("*.md")
    )
    assert read >= {"ATLAS_PROGRESS", "ATLAS_JAX_CACHE"}
    assert not [v for v in sorted(read) if v not in docs]


TINY = ["--beta1", "0:2pi:4", "--beta2", "0:2pi:4", "--kappa", "0.5", "--q", "0"]


@pytest.mark.parametrize("no_progress", [False, True])
def test_atlas_progress_shows_the_bar_off_a_terminal_unless_no_progress(
    tmp_path, capsys, monkeypatch, no_progress
):
    monkeypatch.setenv("ATLAS_PROGRESS", "1")
    argv = ["generate", *TINY, "--outputs", "class_code", "--out", str(tmp_path / "a.nc")]
    assert main(argv + ["--no-progress"] * no_progress) == 0
    err = capsys.readouterr().err  # pytest's capture: not a terminal
    bar = re.search(r"atlas custom: +\d+%\|", err)
    assert (bar is None) == no_progress, err
