"""The backend's self-check record as the certified driver consults it."""

import numpy as np
import pytest

from atlas.core import backend, config, points
from atlas.core.config import CACHE_ENV


def test_the_record_file_is_found_once_per_cache_setting(tmp_path, monkeypatch):
    """The certified driver consults the record on every call: where it lives is found (and its
    directory created) once per cache setting, not once per call; a record written later is
    still read."""
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "a"))
    found, real = [], config.compile_cache_dir
    monkeypatch.setattr(config, "compile_cache_dir", lambda: found.append(1) or real())
    one = np.ones(3)
    for _ in range(5):
        points.spectral_points(one, 0 * one, 0 * one, one, 1.0, 0.0, 0.0, names=("stable_SS",))
    assert len(found) == 1
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "b"))
    backend.require_trusted()
    assert len(found) == 2 and (tmp_path / "b").is_dir()
    backend.record({"passed": False, "disagreements": 1, "when": "now"})
    with pytest.raises(backend.BackendFailed, match="failed atlas selftest"):
        backend.require_trusted()
    monkeypatch.setenv(CACHE_ENV, "0")
    assert backend.recorded() is None


@pytest.mark.parametrize(
    "flags, refused",
    [
        ("--xla_cpu_enable_fast_math=true", True),
        ("--xla_cpu_multi_thread_eigen=false --xla_cpu_enable_fast_math", True),
        ("--xla_cpu_enable_fast_min_max=1", True),
        ("--xla_cpu_enable_fast_math=false --xla_cpu_enable_fast_min_max=False", False),
        ("--xla_cpu_multi_thread_eigen=false", False),
    ],
)
def test_fast_math_flags_certify_nothing(monkeypatch, flags, refused):
    """Under ``--xla_cpu_enable_fast_math`` XLA reassociates sums (measured: ``(a + b) - a`` gives
    ``b``, ``(a + b) + b`` gives ``a + 2 b``), which no error bound of the kernels covers: the
    certified driver refuses, naming the flag; the flags switched off are accepted."""
    monkeypatch.setenv("XLA_FLAGS", flags)
    one = np.ones(2)
    args = (one, 0 * one, 0 * one, one, 1.0, 0.0, 0.0)
    if refused:
        with pytest.raises(backend.BackendFailed, match="XLA_FLAGS: xla_cpu_enable_fast_m"):
            points.spectral_points(*args, names=("stable_SS",))
    else:
        assert (points.spectral_points(*args, names=("stable_SS",))["stable_SS"] == 2).all()
