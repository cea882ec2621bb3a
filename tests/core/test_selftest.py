"""``atlas selftest``: passes on this CPU; a certified sign broken on purpose (``det B`` flipped
wherever it is certified) gives disagreements, exit code 1, a failed record, and the certified
driver then refuses to run until a passing check is recorded."""

import jax
import jax.numpy as jnp
import pytest

from atlas import cli
from atlas.core import (
    backend,
    contact_modes,
    enclosures,
    hurwitz,
    points,
    rootfree,
    signs,
    spectral,
    undamped,
    warm,
)
from atlas.core.config import CACHE_ENV

ONE_POINT = (1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0)  # B = I, kappa = 1, undamped


@pytest.mark.e2e
def test_selftest_passes_on_cpu(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path))  # the record goes here
    monkeypatch.setenv(warm.EXECUTABLE_ENV, "0")  # no executables compiled for a throw-away cache
    assert cli.main(["selftest"]) == 0
    out = capsys.readouterr().out
    assert "PASSED: 0 disagreements" in out and "ns/point" in out
    rec = backend.recorded()
    assert rec["passed"] and rec["disagreements"] == 0 and rec["points"] > 1000


def _flipped(real):
    def det2_sign(*args):
        s = real(*args)
        return jnp.where(s == signs.UNKNOWN, s, -s)

    return det2_sign


@pytest.mark.e2e
def test_a_broken_sign_fails_and_the_backend_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path))
    monkeypatch.setenv(warm.EXECUTABLE_ENV, "0")
    args = ["selftest", "--suites", "near_detB,class_boundaries", "--dtypes", "float64"]
    with pytest.MonkeyPatch.context() as mp:
        for mod in (contact_modes, rootfree, spectral, hurwitz, enclosures, undamped):
            mp.setattr(mod, "det2_sign", _flipped(signs.det2_sign))
        jax.clear_caches()  # the kernels retrace with the broken sign
        try:
            assert cli.main(args) == 1
        finally:
            mp.undo()
            jax.clear_caches()
    out = capsys.readouterr().out
    assert "FAILED" in out and "disagrees:" in out
    assert backend.recorded()["passed"] is False
    with pytest.raises(backend.BackendFailed, match="failed atlas selftest"):
        points.spectral_points(*ONE_POINT)
    assert cli.main(["generate", "--beta1", "0:2pi:4", "--beta2", "0:2pi:4", "--out",
                     str(tmp_path / "a.nc")]) == 1  # fmt: skip
    assert "failed atlas selftest" in capsys.readouterr().err
    # the unbroken kernels pass again, and are trusted again
    assert cli.main(args) == 0
    assert backend.recorded()["passed"] is True
    assert points.spectral_points(*ONE_POINT)["stable_SS"] != 3


def test_no_record_without_a_cache(monkeypatch):
    monkeypatch.setenv(CACHE_ENV, "0")
    assert backend.recorded() is None and backend.record({"passed": False}) is None
    backend.require_trusted()  # nothing recorded: trusted
