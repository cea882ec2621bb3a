"""The model-dependence map of the Fig. 1 plane: verdicts over every contact model against one model.

The plane is the ``n x n`` offset grid of ``(beta1, beta2)`` in ``[0, 2 pi)`` of
:func:`atlas.paper.figure_models.model_dependence_map` (no cell on a class line when ``n`` is a
multiple of 4), the box the whole model space.  Per field (``SS``: :func:`atlas.core.model_box.
ss_over_models`, ``II``: :func:`atlas.core.ii_over_models.ii_over_models`, both codes) one row:
ns per point of the map (warm: a first call compiles, then the minimum of repeats), ns per point of
the single-model kernel on the same plane in the same run (``ss_verdict``; the certified driver
:func:`atlas.core.points.spectral_points` for II at one model), the codes left undecided before and
after settlement, and the share of the plane in each region.
"""

from __future__ import annotations

import numpy as np

from atlas.bench.timing import log, timeit

__all__ = ["COLUMNS", "measure", "section"]

#: the one model of the single-model kernels (kappa, q1, q2)
ONE_MODEL = (0.5, 0.1, 0.1)
#: the columns of the section's table
COLUMNS = (
    "field", "points", "seconds", "ns_per_point", "one_model_ns_per_point", "over_one_model",
    "undecided_before", "undecided_after", "stable", "unstable", "depends", "undecided",
)  # fmt: skip


def plane(n: int) -> tuple:
    """Direction components ``(c1, s1, c2, s2)`` of the ``n x n`` offset plane (broadcastable)."""
    from atlas.core.contact_modes import direction  # noqa: PLC0415 - the report imports this

    c, s = direction((np.arange(n) + 0.5) * (2 * np.pi / n))
    return c[:, None], s[:, None], c[None, :], s[None, :]


def _one_model(field: str, g) -> float:
    """Seconds of the single-model kernel of ``field`` on the plane ``g`` (warm minimum)."""
    import jax  # noqa: PLC0415 - JAX only when measured

    from atlas.core.hurwitz import ss_verdict  # noqa: PLC0415
    from atlas.core.points import spectral_points  # noqa: PLC0415

    if field == "SS":
        fn = jax.jit(ss_verdict)
        return timeit(lambda: fn(*g, *ONE_MODEL).block_until_ready())
    names = ("consistent_II", "stable_II")
    return timeit(lambda: np.asarray(spectral_points(*g, *ONE_MODEL, names=names)["stable_II"]))


def _row(field: str, n: int, repeats: int) -> dict:
    """One row of :func:`measure`."""
    from atlas.core import ii_over_models as iim  # noqa: PLC0415 - the report imports this
    from atlas.core import model_box as mb  # noqa: PLC0415
    from atlas.core.verdicts import OverModels  # noqa: PLC0415

    g = plane(n)
    box = mb.model_box()
    run = mb.ss_over_models if field == "SS" else iim.ii_over_models
    code = "ss_over_models" if field == "SS" else "ii_stable_over_models"
    out: dict = {}

    def call():
        out["r"] = run(*g, box)

    seconds = timeit(call, budget=0.0, max_repeats=repeats, min_repeats=repeats)
    r, points = out["r"], n * n
    one = _one_model(field, g)
    codes = np.asarray(r[code])
    share = {v.name.lower(): np.count_nonzero(codes == int(v)) / points for v in OverModels}
    return dict(
        field=field, points=points, seconds=seconds, ns_per_point=seconds / points * 1e9,
        one_model_ns_per_point=one / points * 1e9, over_one_model=seconds / one,
        undecided_before=r.stats["undecided_before"], undecided_after=r.stats["undecided_after"],
        **share,
    )  # fmt: skip


def measure(cfg) -> list[dict]:
    """The rows of ``cfg["model_box_map"]`` (``n``: cells per axis, one number or one per field,
    ``fields``: ``SS`` / ``II``, ``repeats``); none where the configuration leaves it out."""
    spec = cfg.get("model_box_map")
    if not spec:
        return []
    rows = []
    for field in spec["fields"]:
        n = spec["n"][field] if isinstance(spec["n"], dict) else spec["n"]
        log(f"model-box map {field}, {n}^2 Fig. 1 plane, whole model space")
        rows.append(_row(field, n, spec.get("repeats", 2)))
    return rows


def section(rows) -> list[str]:
    """The Markdown of ``bench.md``'s section (empty if not measured)."""
    if not rows:
        return []
    from atlas.bench.report import table  # noqa: PLC0415 - the report imports this module

    return [
        "### Model-dependence map of the Fig. 1 plane\n",
        "Verdicts over every contact model (kappa > 0, q1, q2 >= 0) on the offset grid of the "
        "Fig. 1 plane: `ss_over_models` (SS) and `ii_over_models` (II consistency and stability, "
        "shares of II stability), with settlement (II: no proofs over unbounded boxes), warm "
        "(minimum of repeats after a first call); the single-model kernel on the same plane in "
        f"the same run at kappa, q1, q2 = {ONE_MODEL} (`ss_verdict`; `spectral_points` for "
        "II). Undecided = codes left open before / after settlement; shares of the plane in "
        "each region.\n",
        table(rows, COLUMNS),
        "",
    ]
