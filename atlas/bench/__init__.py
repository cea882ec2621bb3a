"""Layer 4, measurement: ``atlas bench`` (speed against error, scaling, hard cases, simulation)."""

from atlas.bench.runner import CONFIG, run

__all__ = ["CONFIG", "run"]
