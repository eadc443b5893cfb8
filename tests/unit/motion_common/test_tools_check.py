"""motion_common.tools_check: a launch argument that needs a missing program is refused
with the install command, before anything starts."""

import os
import stat

from motion_common.tools_check import missing_tool_message


def test_a_missing_rviz_names_the_apt_package():
    assert missing_tool_message("rviz", which=lambda _: None) == "rviz is not installed: sudo apt-get install rviz"


def test_an_installed_tool_gives_no_message():
    assert missing_tool_message("rviz", which=lambda name: f"/usr/bin/{name}") is None


def test_a_program_whose_package_has_another_name_suggests_the_package():
    assert (
        missing_tool_message("xvfb-run", which=lambda _: None) == "xvfb-run is not installed: sudo apt-get install xvfb"
    )


def test_the_default_lookup_is_the_real_path(tmp_path, monkeypatch):
    # An executable on PATH counts as installed; the same name off PATH does not.
    tool = tmp_path / "fake-viewer"
    tool.write_text("#!/bin/sh\n")
    tool.chmod(tool.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("PATH", str(tmp_path))
    assert missing_tool_message("fake-viewer") is None
    monkeypatch.setenv("PATH", os.devnull)
    assert missing_tool_message("fake-viewer") == "fake-viewer is not installed: sudo apt-get install fake-viewer"
