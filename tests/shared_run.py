"""A computation run once per test session and shared by the pytest-xdist workers (the session's
``atlas paper`` run, the tiny bench): :func:`shared_run`."""

import os

import pytest


def shared_run(tmp_path_factory, name: str, compute) -> tuple:
    """``compute(out)`` (a dict of picklable results) run once per test session into the
    directory ``out`` (``<session tmp>/<name>``), and ``(out, its dict)``: under pytest-xdist the
    first worker to create the directory runs it and the others wait for its result (a pickle
    beside it; a failure there fails them too)."""
    import pickle
    import time

    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent  # shared by the workers of this session
    out, done = root / name, root / f"{name}.pickle"
    try:
        out.mkdir()
    except FileExistsError:  # another worker runs it
        deadline = time.monotonic() + 1800
        while not done.exists():
            if time.monotonic() > deadline:
                pytest.fail(f"the shared run {name} did not finish")
            time.sleep(0.5)
        got = pickle.loads(done.read_bytes())
        if isinstance(got, str):
            pytest.fail(f"the shared run {name} failed: {got}")
        return out, got
    try:
        got = compute(out)
    except BaseException as e:
        got = f"{type(e).__name__}: {e}"
        raise
    finally:
        tmp = done.with_name(done.name + ".tmp")
        tmp.write_bytes(pickle.dumps(got))
        os.replace(tmp, done)
    return out, got
