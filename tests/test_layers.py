"""The layer contract (pyproject ``[tool.importlinter]``) is broken by a copy of the package in which a
lower layer imports a higher one, so the ``lint-imports`` step of ``.ci/run`` (which checks the
package itself) can fail."""

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


@pytest.mark.e2e
@pytest.mark.parametrize(
    "module, line, contract",
    [
        ("core/verdicts.py", "import atlas.paper.tables  # noqa", "layers"),
        ("data/scene.py", "import atlas.dynamics.model  # noqa", "layers"),
        ("core/contact_modes.py", "import xarray  # noqa", "core is mathematics"),
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
