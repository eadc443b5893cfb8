"""Saves clean up after killed saves: the temporary files a killed writer left are removed
by the next save of the same file (or at start), never a live one."""

import os
import signal
import subprocess
import sys
import textwrap
import time

from motion_common.atomic_file import STALE_TEMP_AGE_S, remove_stale_temp_files, write_atomic


def leftover(folder, name, age_s, tag="abc123"):
    path = os.path.join(folder, f".{name}.{tag}.tmp")
    with open(path, "w") as stream:
        stream.write("half a program")
    stamp = time.time() - age_s
    os.utime(path, (stamp, stamp))
    return path


def test_next_save_removes_old_leftovers_of_that_file_only(tmp_path):
    old = leftover(tmp_path, "a.yaml", STALE_TEMP_AGE_S + 5)
    fresh = leftover(tmp_path, "a.yaml", 1.0, "def456")  # a save in progress right now
    other = leftover(tmp_path, "b.yaml", STALE_TEMP_AGE_S + 5)
    write_atomic(str(tmp_path / "a.yaml"), "x: 1\n")
    assert not os.path.exists(old) and os.path.exists(fresh) and os.path.exists(other)
    other = str(other)
    assert sorted(remove_stale_temp_files(str(tmp_path))) == [str(other)]
    assert remove_stale_temp_files(str(tmp_path / "missing")) == []


def test_kill_9_during_saves_leaves_nothing_after_the_next_save(tmp_path):
    """A writer killed mid-save leaves at most its temporary file; once stale, the next save
    removes it (the clock is injected: no waiting)."""
    target = tmp_path / "prog.yaml"
    script = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {os.path.dirname(os.path.dirname(os.path.abspath(__import__("motion_common").__file__)))!r})
        from motion_common.atomic_file import write_atomic
        while True:
            write_atomic({str(target)!r}, "x: " + "1" * 200000 + "\\n")
    """)
    for _ in range(5):
        proc = subprocess.Popen([sys.executable, "-c", script])
        time.sleep(0.3)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    later = time.time() + STALE_TEMP_AGE_S + 1
    remove_stale_temp_files(str(tmp_path), "prog.yaml", now=later)
    assert [p for p in os.listdir(tmp_path) if p.endswith(".tmp")] == []
    assert target.read_text().startswith("x: 1")
