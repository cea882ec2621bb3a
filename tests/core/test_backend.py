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
