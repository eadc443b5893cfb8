"""pybullet's import and connect print nothing (its build-time line went to stderr, its
argv line to stdout, on every session start)."""

import subprocess
import sys

from ..conftest import ROOT


def test_import_and_connect_are_silent():
    code = (
        "import sys; sys.path.insert(0, {!r})\n"
        "from motion_common.quiet_pybullet import connect, bullet_client, pybullet\n"
        "connect(pybullet.DIRECT); bullet_client(pybullet.DIRECT)\n"
        "print('done')\n"
    ).format(f"{ROOT}/src/motion_common")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert result.stdout == "done\n" and result.stderr == ""


def test_output_inside_the_block_is_dropped_and_after_it_shown():
    code = (
        "import sys; sys.path.insert(0, {!r})\n"
        "from motion_common.native_output import native_output_silenced\n"
        "with native_output_silenced():\n"
        "    print('hidden'); print('hidden too', file=sys.stderr)\n"
        "print('shown'); print('shown too', file=sys.stderr)\n"
    ).format(f"{ROOT}/src/motion_common")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert (result.stdout, result.stderr) == ("shown\n", "shown too\n")
