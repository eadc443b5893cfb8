"""scripts/setup finds the Debian packages a machine lacks and installs them, whatever
dpkg-query says of packages it has never seen (it exits 1 for those)."""

import os
import stat
import subprocess

from ..conftest import ROOT

DPKG_QUERY = """#!/bin/sh
# Knows every package but chromium-driver (never installed: dpkg-query says so and exits 1).
status=0
for pkg in "$@"; do
  case "$pkg" in
    -W|-f=*) ;;
    chromium-driver) echo "dpkg-query: no packages found matching $pkg" >&2; status=1;;
    *) printf '%s:install ok installed\\n' "$pkg";;
  esac
done
exit $status
"""
APT_GET = """#!/bin/sh
echo "$@" >> "$(dirname "$0")/apt-get.calls"
"""


def _stub(folder, name, text):
    path = folder / name
    path.write_text(text)
    path.chmod(path.stat().st_mode | stat.S_IXUSR)


def test_a_package_dpkg_has_never_seen_is_installed(tmp_path):
    _stub(tmp_path, "dpkg-query", DPKG_QUERY)
    _stub(tmp_path, "apt-get", APT_GET)
    _stub(tmp_path, "sudo", '#!/bin/sh\nexec "$@"\n')
    result = subprocess.run(
        [os.path.join(ROOT, "scripts", "setup"), "--test"],
        env={**os.environ, "PATH": f"{tmp_path}:{os.environ['PATH']}"},
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=1800,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "installing Debian packages: chromium-driver" in result.stdout, result.stdout
    calls = (tmp_path / "apt-get.calls").read_text().splitlines()
    assert calls[0] == "update -qq" and calls[1].split()[-1] == "chromium-driver", calls
