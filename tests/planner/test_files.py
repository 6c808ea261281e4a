"""Atomic output: permissions follow the umask, failures never clobber existing files, and
a full disk is named by the file being written."""

import errno
import os
import stat

import pytest

from jaxspline.planner.files import atomic_path, atomic_write_text, refuse_overwrite


def test_written_file_has_umask_permissions_and_content(tmp_path):
    old = os.umask(0o022)
    try:
        p = atomic_write_text(tmp_path / "a.txt", "hello\n")
    finally:
        os.umask(old)
    assert p.read_text() == "hello\n"
    assert stat.S_IMODE(os.stat(p).st_mode) == 0o644  # not mkstemp's 0600
    assert [f.name for f in tmp_path.iterdir()] == ["a.txt"]  # no temp file left


def test_refuses_to_overwrite_without_force(tmp_path):
    p = tmp_path / "plan.json"
    p.write_text("user data")
    with pytest.raises(FileExistsError, match="plan.json"):
        atomic_write_text(p, "new", force=False)
    assert p.read_text() == "user data"
    atomic_write_text(p, "new", force=True)
    assert p.read_text() == "new"
    refuse_overwrite(tmp_path / "absent.json", force=False)  # no error


def test_failed_write_leaves_existing_file_untouched(tmp_path):
    p = tmp_path / "plot.png"
    p.write_text("previous result")
    with pytest.raises(RuntimeError), atomic_path(p, suffix=".tmp.png") as tmp:
        with open(tmp, "w") as fh:
            fh.write("half a fig")
        raise RuntimeError("disk full")
    assert p.read_text() == "previous result"
    assert [f.name for f in tmp_path.iterdir()] == ["plot.png"]


class _FullFile:
    """A file open for writing on a full disk: every write fails as the kernel says."""

    def __init__(self, *args, **kwargs):
        pass

    def write(self, text):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))  # names no file

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_a_full_disk_is_named_by_the_file_being_written(tmp_path, monkeypatch):
    from jaxspline.planner import files

    p = tmp_path / "page.html"
    monkeypatch.setattr(files, "open", _FullFile, raising=False)
    with pytest.raises(OSError) as exc:
        atomic_write_text(p, "x")
    assert (exc.value.errno, exc.value.filename) == (errno.ENOSPC, str(p))
    assert list(tmp_path.iterdir()) == []  # no temporary file left


def test_a_real_full_disk_is_named_by_the_file_being_written(tmp_path):
    from _full_disk import full_disk

    with full_disk(tmp_path) as full:
        p = full / "sol.json"
        with pytest.raises(OSError) as exc:
            atomic_write_text(p, "x" * 200_000)
        assert (exc.value.errno, exc.value.filename) == (errno.ENOSPC, str(p))
        assert [f.name for f in full.iterdir()] == ["filler"]  # no temporary file left
