"""The layer contract (pyproject ``[tool.importlinter]``): kept by the package, broken by a copy of it
in which a lower layer imports a higher one (so the check can fail)."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINT = Path(sys.executable).with_name("lint-imports")


def _lint(root: Path) -> subprocess.CompletedProcess:
    if not LINT.exists():
        if os.environ.get("CI"):
            raise AssertionError("lint-imports missing: install the [test] extra")
        pytest.skip("import-linter not installed")
    env = dict(os.environ, PYTHONPATH=str(root))
    return subprocess.run(
        [str(LINT), "--no-cache", "--config", str(root / "pyproject.toml")],
        cwd=root,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_package_keeps_the_layer_contracts():
    r = _lint(ROOT)
    assert r.returncode == 0, r.stdout[-3000:]
    assert "broken" not in r.stdout.lower().replace("0 broken", "")


@pytest.mark.parametrize(
    "module, line, contract",
    [
        ("core/verdicts.py", "import atlas.paper.tables  # noqa", "layers"),
        ("data/scene.py", "import atlas.dynamics.model  # noqa", "layers"),
        ("core/mechanics.py", "import xarray  # noqa", "core is mathematics"),
    ],
)
def test_a_lower_layer_importing_upward_breaks_the_contract(tmp_path, module, line, contract):
    shutil.copytree(
        ROOT / "atlas", tmp_path / "atlas", ignore=shutil.ignore_patterns("__pycache__")
    )
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    target = tmp_path / "atlas" / module
    target.write_text(target.read_text() + "\n" + line + "\n")
    r = _lint(tmp_path)
    assert r.returncode != 0
    broken = r.stdout.split("Broken contracts")[-1]
    assert contract in broken, r.stdout[-3000:]
