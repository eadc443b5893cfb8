"""motion_commander.program: validation with clear errors, round trip, and crash-safe saving."""

import os
import random
import signal
import subprocess
import sys
import textwrap
import time

import pytest
import yaml

from ..conftest import ROOT

APPS = os.path.join(ROOT, "src", "motion_apps")
if APPS not in sys.path:
    sys.path.insert(0, APPS)

from motion_commander.program import Program, ProgramError, Waypoint, load_program, save_program  # noqa: E402

JOINTS = [0.1, -1.4, 1.6, -1.8, -1.57, 0.1]


def make_program(count=3, robot="ur5e", tag="a"):
    return Program(
        robot=robot,
        waypoints=[
            Waypoint(
                f"{tag}{i}",
                [-0.4, -0.2 + 0.01 * i, 0.2],
                [1.0, 0.0, 0.0, 0.0],
                list(JOINTS),
                ["none", "grip", "release"][i % 3],
                0.5,
            )
            for i in range(count)
        ],
    )


def write(tmp_path, data, name="p.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data) if not isinstance(data, str) else data)
    return str(path)


def test_round_trip(tmp_path):
    program = make_program()
    path = save_program(program, str(tmp_path / "sub" / "prog.yaml"))
    loaded = load_program(path)
    assert loaded == program
    assert "format_version: 1" in open(path).read()


@pytest.mark.parametrize(
    "mutate, expected",
    [
        (lambda d: d.pop("robot"), "missing ['robot']"),
        (lambda d: d.update(format_version=2), "format_version 2 is not supported"),
        (lambda d: d.update(colour="red"), "unknown parameter 'colour'"),
        (lambda d: d.update(waypoints=[]), "no waypoints"),
        (lambda d: d["waypoints"][1].pop("joints"), "waypoint 1 ('a1'): missing ['joints']"),
        (lambda d: d["waypoints"][1]["pose"].pop("orientation"), "waypoint 1 ('a1'): missing ['pose.orientation']"),
        (lambda d: d["waypoints"][2].update(action="drop"), "waypoint 2 ('a2')"),
        (lambda d: d["waypoints"][0].update(speed=0.0), "parameter 'speed' (1) must be in (0, 1]"),
        (lambda d: d["waypoints"][0].update(speed=1.5), "must be in (0, 1]"),
        (lambda d: d["waypoints"][1]["pose"].update(position=[0.1, 0.2]), "must have 3 values"),
        (lambda d: d["waypoints"][1]["pose"].update(orientation=[1, 1, 0, 0]), "not a unit quaternion"),
        (lambda d: d["waypoints"][1].update(joints=[0.0, float("nan"), 0, 0, 0, 0]), "finite numbers"),
        (lambda d: d["waypoints"][1].update(joints=[0.0] * 5), "waypoint 1 ('a1'): 5 joints, waypoint 0 has 6"),
        (lambda d: d["waypoints"][2].update(name="a0"), "name 'a0' already used by waypoint 0"),
        (lambda d: d["waypoints"][1].update(grip=True), "unknown parameter 'grip'"),
    ],
)
def test_invalid_programs_are_refused_naming_file_and_waypoint(tmp_path, mutate, expected):
    data = make_program().to_dict()
    mutate(data)
    path = write(tmp_path, data)
    with pytest.raises(ProgramError) as err:
        load_program(path)
    assert path in str(err.value)
    assert expected in str(err.value)


def test_unreadable_and_broken_files(tmp_path):
    with pytest.raises(ProgramError, match="cannot read"):
        load_program(str(tmp_path / "nope.yaml"))
    with pytest.raises(ProgramError, match="not valid YAML"):
        load_program(write(tmp_path, "robot: [unclosed"))
    with pytest.raises(ProgramError, match="holds a mapping"):
        load_program(write(tmp_path, "- 1\n- 2\n"))


def test_an_invalid_program_is_never_written(tmp_path):
    path = str(tmp_path / "p.yaml")
    save_program(make_program(), path)
    bad = make_program()
    bad.waypoints[0].speed = 2.0
    with pytest.raises(ProgramError):
        save_program(bad, path)
    assert load_program(path) == make_program()
    assert [name for name in os.listdir(tmp_path) if name.endswith(".tmp")] == []


SAVER = textwrap.dedent("""
    import sys
    sys.path[:0] = {paths!r}
    from motion_commander.program import Program, Waypoint, save_program
    J = [0.1, -1.4, 1.6, -1.8, -1.57, 0.1]
    def make(tag, count):
        return Program(robot="ur5e", waypoints=[Waypoint(f"{{tag}}{{i}}", [-0.4, -0.2 + 0.001 * i, 0.2],
                       [1.0, 0.0, 0.0, 0.0], J, "none", 0.5) for i in range(count)])
    programs = [make("old", 60), make("new", 40)]
    save_program(programs[0], sys.argv[1])
    print("ready", flush=True)
    i = 1
    while True:
        save_program(programs[i % 2], sys.argv[1])
        i += 1
""")


def test_a_killed_save_leaves_the_old_or_the_new_program(tmp_path):
    """SIGKILL a process saving old/new programs in a loop, 50 times at random (seeded)
    moments: the file always parses and is exactly one of the two programs."""
    paths = [os.path.join(ROOT, "src", p) for p in ("motion_common", "motion_commander")]
    script = tmp_path / "saver.py"
    script.write_text(SAVER.format(paths=paths))
    target = str(tmp_path / "prog.yaml")
    rng = random.Random(20240601)
    seen = {"old": 0, "new": 0}
    started = time.monotonic()
    for _ in range(50):
        proc = subprocess.Popen([sys.executable, str(script), target], stdout=subprocess.PIPE)
        try:
            assert proc.stdout.readline().strip() == b"ready"
            time.sleep(rng.uniform(0.0, 0.05))
        finally:
            proc.send_signal(signal.SIGKILL)
            proc.wait(10)
        program = load_program(target)  # must parse
        tag = program.waypoints[0].name[:3]
        assert tag in seen
        assert len(program.waypoints) == (60 if tag == "old" else 40)
        assert all(w.name.startswith(tag) for w in program.waypoints), "mixed program"
        seen[tag] += 1
    assert seen["old"] and seen["new"], f"the kills never hit both states: {seen}"
    assert time.monotonic() - started < 30.0
