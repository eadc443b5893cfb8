"""motion_common.atomic_file: a saved file is a normal, readable file, written whole."""

import os
import stat

from motion_common.atomic_file import write_atomic


def test_written_file_has_the_umask_mode_and_the_new_text(tmp_path):
    old = os.umask(0o022)
    try:
        path = write_atomic(str(tmp_path / "a" / "program.yaml"), "old\n")
        write_atomic(path, "new\n")
    finally:
        os.umask(old)
    assert open(path).read() == "new\n"
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o644
    assert os.listdir(os.path.dirname(path)) == ["program.yaml"]  # no temporary left behind
