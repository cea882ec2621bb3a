"""``atlas.bench.config``: the runs' sizes, and where a run writes by default."""

import shutil
import subprocess
from pathlib import Path

import pytest

from atlas import cli
from atlas.bench import config
from atlas.bench.suites import HEADLINE_CASES

REPO = Path(__file__).resolve().parents[2]


def test_every_mode_sets_the_same_keys():
    keys = set(config.CONFIG["full"])
    assert all(set(cfg) == keys for cfg in config.CONFIG.values())


@pytest.mark.parametrize("mode", ["quick", "tiny"])
def test_smaller_runs_are_smaller(mode):
    full, cfg = config.CONFIG["full"], config.CONFIG[mode]
    assert max(cfg["res"]) <= max(full["res"]) and cfg["ref_factor"] <= full["ref_factor"]
    assert cfg["large_n"] == 0 and cfg["suite_points"] and not cfg["generate_points"]
    assert set(cfg["dtypes"]) <= set(full["dtypes"]) == {"float32", "float64"}
    # the headline needs the undamped and the damped equal-q case
    names = {c[0] for c in cfg["cases"]}
    assert {"q=0", "q=0.1"} <= names <= {case for case, _ in HEADLINE_CASES.values()}


def test_mode_name():
    assert config.mode_name() == "full"
    assert config.mode_name(quick=True) == "quick"
    assert config.mode_name(quick=True, config="tiny") == "tiny"
    with pytest.raises(ValueError, match="^config: must be one of full, quick, tiny, got 'huge'$"):
        config.mode_name(config="huge")


def test_quick_writes_outside_the_tracked_outputs():
    assert config.default_out("full") == Path("outputs")
    assert config.default_out("quick") == Path("outputs/quick")
    # the CLI leaves the choice to the mode unless --out is given
    assert cli.build_parser().parse_args(["bench", "--quick"]).out is None
    assert cli.build_parser().parse_args(["bench", "--out", "x"]).out == "x"


@pytest.mark.skipif(shutil.which("git") is None, reason="git not installed")
@pytest.mark.parametrize("mode", ["quick", "tiny"])
def test_quick_outputs_are_ignored_by_git(mode):
    path = config.default_out(mode) / "bench.md"
    p = subprocess.run(["git", "check-ignore", "-q", str(path)], cwd=REPO, check=False)
    if p.returncode == 128:
        pytest.skip("not a git checkout")
    assert p.returncode == 0, f"{path} is not ignored by git"
    p = subprocess.run(["git", "check-ignore", "-q", "outputs/bench.md"], cwd=REPO, check=False)
    assert p.returncode == 1  # the full report is tracked
