"""Store directories (atlas.data.store_guard): never the working or home directory, replaced only
if the project wrote them and by renames, held by one writer at a time."""

import json
import os
import socket
import subprocess
import sys

import pytest

from atlas.data import store_guard as G


def _ours(path):
    return os.path.exists(os.path.join(path, "marker"))


@pytest.mark.parametrize("place", ["", " ", ".", "..", "~", "/"])
def test_working_home_and_root_are_never_a_store(place, tmp_path, monkeypatch):
    (tmp_path / "w").mkdir()
    monkeypatch.chdir(tmp_path / "w")
    with pytest.raises(ValueError, match="^store: "):
        G.check_place(os.path.expanduser(place) if place == "~" else place)


def test_only_a_marked_directory_is_replaceable(tmp_path):
    assert G.check_replaceable(str(tmp_path / "new"), _ours, "a store") is False
    (tmp_path / "empty").mkdir()
    assert G.check_replaceable(str(tmp_path / "empty"), _ours, "a store") is True
    (tmp_path / "file").write_text("x")
    with pytest.raises(ValueError, match="^store: .*not a directory"):
        G.check_replaceable(str(tmp_path / "file"), _ours, "a store")
    (tmp_path / "theirs").mkdir()
    (tmp_path / "theirs" / "keep.txt").write_text("x")
    with pytest.raises(ValueError, match="^store: .*not a store \\(no marker\\)"):
        G.check_replaceable(str(tmp_path / "theirs"), _ours, "a store")
    (tmp_path / "theirs" / "marker").write_text("")
    assert G.check_replaceable(str(tmp_path / "theirs"), _ours, "a store") is True


def test_install_renames_and_keeps_the_old_store_if_the_new_cannot_go_in(tmp_path, monkeypatch):
    old, new = tmp_path / "s", tmp_path / ".s.tmp"
    old.mkdir()
    (old / "a").write_text("old")
    new.mkdir()
    (new / "a").write_text("new")
    G.install(str(new), str(old))
    assert (old / "a").read_text() == "new" and sorted(os.listdir(tmp_path)) == ["s"]
    new.mkdir()
    replace = os.replace

    def fail_second(src, dst):
        if src == str(new):
            raise OSError(28, "No space left on device")
        replace(src, dst)

    monkeypatch.setattr(os, "replace", fail_second)
    with pytest.raises(OSError):
        G.install(str(new), str(old))
    assert (old / "a").read_text() == "new"


def test_a_live_writer_holds_the_store(tmp_path):
    store = str(tmp_path / "s")
    lock = G.lock_path(store)
    with open(lock, "w") as fh:  # a lock of a live process of this host (our parent)
        json.dump({"pid": os.getppid(), "host": socket.gethostname()}, fh)
    with pytest.raises(BlockingIOError, match=f"^store: .*being written by process {os.getppid()}"):
        with G.held(store):
            pass
    assert os.path.exists(lock)
    with open(lock, "w") as fh:  # another host: never taken over
        json.dump({"pid": 1, "host": "elsewhere"}, fh)
    with pytest.raises(BlockingIOError, match="on elsewhere"):
        with G.held(store):
            pass


def test_a_lock_of_a_finished_process_is_taken_over_and_released(tmp_path):
    store = str(tmp_path / "s")
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    with open(G.lock_path(store), "w") as fh:
        json.dump({"pid": int(gone.stdout), "host": socket.gethostname()}, fh)
    with G.held(store) as lock:
        with open(lock) as fh:
            assert json.load(fh)["pid"] == os.getpid()
        with pytest.raises(BlockingIOError):  # held: even this process cannot take it twice
            with G.held(store):
                pass
    assert not os.path.exists(G.lock_path(store))


def _dead_pid() -> int:
    """The pid of a process of this host that has finished."""
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    return int(gone.stdout)


def _leftover(tmp_path, pid, text="old"):
    """The old store ``install`` moved aside as ``.s.old.PID``, its process killed before the
    new one went in or before the old one was removed."""
    old = tmp_path / f".s.old.{pid}"
    old.mkdir()
    (old / "marker").write_text("")
    (old / "a").write_text(text)
    return old


def test_a_killed_replacement_is_finished_by_the_next_writer(tmp_path, capsys):
    store, pid = tmp_path / "s", _dead_pid()
    # killed between the renames: the old store is the only copy, renamed back
    _leftover(tmp_path, pid)
    with G.held(str(store), ours=_ours):
        assert (store / "a").read_text() == "old"
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"store: restored {store} from ")
    assert f"process {pid}" in err[0]
    assert sorted(os.listdir(tmp_path)) == ["s"]
    # killed after the renames: the new store (ours) is in place, the old copy removed
    old = _leftover(tmp_path, pid, "older")
    with G.held(str(store), ours=_ours):
        pass
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"store: removed the old copy {old} ")
    assert sorted(os.listdir(tmp_path)) == ["s"] and (store / "a").read_text() == "old"
    # the store in place is not one we wrote: nothing removed
    (store / "marker").unlink()
    _leftover(tmp_path, pid)
    with G.held(str(store), ours=_ours):
        pass
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"store: kept {old} ")
    assert sorted(os.listdir(tmp_path)) == [".s.old." + str(pid), "s"]


def test_a_leftover_of_a_live_process_is_left_alone(tmp_path, capsys):
    """A live process (our parent) may be replacing the store right now: never touched."""
    old = _leftover(tmp_path, os.getppid())
    G.settle(str(tmp_path / "s"), _ours)
    with G.held(str(tmp_path / "s"), ours=_ours):
        pass
    assert capsys.readouterr().err == ""
    assert sorted(os.listdir(tmp_path)) == [old.name] and (old / "a").read_text() == "old"


def test_settle_restores_before_the_store_is_looked_at(tmp_path, capsys):
    store = tmp_path / "s"
    _leftover(tmp_path, _dead_pid())
    G.settle(str(store), _ours)
    assert (store / "a").read_text() == "old" and sorted(os.listdir(tmp_path)) == ["s"]
    assert capsys.readouterr().err.startswith("store: restored ")
