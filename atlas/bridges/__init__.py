"""Bridges from physics engines to the verdicts (optional extras).

* :mod:`~atlas.bridges.mujoco` a MuJoCo model and state -> contact-space data (``B``, ``a``, an
  approximate ``(k, c)``) -> every verdict (``pip install painleve-atlas[mujoco]``).
"""
