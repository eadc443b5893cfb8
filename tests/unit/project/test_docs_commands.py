"""Every command of the manual works: each line of a ```bash block in README.md and docs/*.md
is run here, in the form that runs without starting ROS:

- a session (scripts/teleop_sim, teach_sim, kitting_sim): with ``--check``, which checks every
  ``name:=value`` (unknown names, files, choices, the robot) and exits without starting ROS;
- ``roslaunch motion_bringup NAME.launch ARGS``: the same check through
  ``scripts/run_session src/motion_bringup/launch/NAME.launch --check ARGS``;
- a generator (scripts/gen_interfaces, scripts/gen_architecture.py): with ``--check``, which
  draws everything and compares it with the committed file;
- a ``--help`` form: as written;
- scripts/setup and scripts/test: the suite itself (scripts/test runs scripts/setup, then
  this file).

Any other line fails: make it one of these forms, or put it in the prose. A fenced block that
is not a command says what it is (```text, ```yaml, ```python). The benchmark commands in the
docs (``bench/run NAME ...``, minutes each) are checked statically: the bench exists and
declares every option used.

The session checks need the --check flag of scripts/run_session (scripts/preflight.py);
until it exists they are expected failures.
"""

import concurrent.futures
import glob
import os
import re
import subprocess

import pytest

from ..conftest import ROOT

DOCS = [os.path.join(ROOT, "README.md")] + sorted(
    path for path in glob.glob(os.path.join(ROOT, "docs", "*.md")) if not path.endswith("interfaces.md")
)
SESSION_SCRIPTS = ("scripts/teleop_sim", "scripts/teach_sim", "scripts/kitting_sim")
GENERATORS = ("scripts/gen_interfaces", ".venv/bin/python scripts/gen_architecture.py")
# Run by the suite itself, not from here: scripts/test is the suite, and it runs scripts/setup first.
THE_SUITE = ("scripts/setup", "scripts/test")
FENCE = re.compile(r"^(\s*)```(.*)$")
ENV_PREFIX = re.compile(r"^((?:[A-Z_][A-Z0-9_]*=(?:\$\([^)]*\)|\S+)\s+)*)(.*)$")


def _rel(path):
    return os.path.relpath(path, ROOT)


def fenced_blocks(path):
    """(info string, first line number, lines) of every fenced block of a Markdown file."""
    blocks, current = [], None
    with open(path, encoding="utf-8") as stream:
        for number, line in enumerate(stream, 1):
            match = FENCE.match(line.rstrip("\n"))
            if match and current is None:
                current = (match.group(2).strip(), number, [])
            elif match:
                blocks.append(current)
                current = None
            elif current is not None:
                current[2].append(line.rstrip("\n"))
    assert current is None, f"{_rel(path)}: a fenced block opened at line {current[1]} is not closed"
    return blocks


def commands(path):
    """(place, command) of every command line of the ```bash blocks: continuation lines
    joined, comments and blank lines dropped."""
    found = []
    for info, first, lines in fenced_blocks(path):
        if info != "bash":
            continue
        pending, start = "", None
        for offset, line in enumerate(lines, 1):
            text = line.strip()
            if start is None:
                start = first + offset
            if text.endswith("\\"):
                pending += text[:-1] + " "
                continue
            text = re.sub(r"(^|\s)#.*$", "", pending + text).strip()
            pending = ""
            if text:
                found.append((f"{_rel(path)}:{start}", text))
            start = None
    return found


ALL_COMMANDS = [item for path in DOCS for item in commands(path)]


def _has_check(script):
    with open(os.path.join(ROOT, script), encoding="utf-8") as stream:
        return "--check" in stream.read()


def runnable(command):
    """(the shell line that runs ``command`` here, whether it needs run_session's --check), or
    (None, the reason) for a line this test does not run. Arguments stay as written, so the
    shell expands $PWD and $(...) as it would for a user."""
    env, rest = ENV_PREFIX.match(command).groups()
    words = rest.split()
    if rest in THE_SUITE:
        return None, "the suite itself"
    if words[0] in SESSION_SCRIPTS:
        if "--help" in words or "--check" in words:
            return command, "--check" in words
        return f"{env}{words[0]} --check{rest[len(words[0]) :]}", True
    launch = re.match(r"roslaunch motion_bringup (\S+\.launch)(.*)$", rest)
    if launch:
        runner = f".venv/bin/python scripts/run_session src/motion_bringup/launch/{launch.group(1)} --check"
        return f"{env}{runner}{launch.group(2)}", True
    if any(rest.startswith(generator) for generator in GENERATORS):
        return (command if "--check" in words else f"{command} --check"), False
    if "--help" in words:
        return command, False
    return None, "not a --help, --check, session or generator form"


def run_one(shell):
    """Exit code and output tail of one shell line."""
    result = subprocess.run(
        ["bash", "-c", f"source catkin_ws/devel/setup.bash && {shell}"],
        cwd=ROOT,
        env={**os.environ, "PWD": ROOT, "MPLBACKEND": "Agg"},
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=300,
    )
    return result.returncode, (result.stdout + result.stderr)[-3000:]


# Each command is a process that mostly starts Python and checks files (2-3 s): the ones the
# collected tests need run a few at a time, once each, and each test waits for its own.
WORKERS = 3


@pytest.fixture(scope="session")
def docs_runs(request):
    """Futures of (exit code, output tail) by shell line, for the collected tests' commands."""
    shells = []
    for item in request.session.items:
        if getattr(item, "originalname", "") == "test_docs_command_runs":
            shell, _ = runnable(item.callspec.params["command"])
            if shell is not None and shell not in shells:
                shells.append(shell)
    # The session scripts run scripts/setup first: once here, so that none of them, running
    # side by side, finds work to do (a build) that another is doing.
    setup = subprocess.run(
        ["scripts/setup"], cwd=ROOT, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=1800
    )
    assert setup.returncode == 0, f"scripts/setup exited {setup.returncode}:\n{(setup.stdout + setup.stderr)[-3000:]}"
    with concurrent.futures.ThreadPoolExecutor(max_workers=WORKERS) as pool:
        yield {shell: pool.submit(run_one, shell) for shell in shells}


@pytest.mark.parametrize("place,command", ALL_COMMANDS, ids=[place for place, _ in ALL_COMMANDS])
def test_docs_command_runs(place, command, docs_runs):
    shell, needs_check = runnable(command)
    if shell is None and needs_check == "the suite itself":
        with open(os.path.join(ROOT, "scripts", "test"), encoding="utf-8") as stream:
            assert "scripts/setup" in stream.read(), "scripts/test no longer runs scripts/setup"
        return
    assert shell is not None, (
        f"{place}: `{command}` cannot be run by the suite ({needs_check}): use a --help or --check form, "
        "or move it into the prose"
    )
    if needs_check and not _has_check("scripts/run_session"):
        pytest.xfail("scripts/run_session has no --check yet: the session check cannot run")
    code, output = docs_runs[shell].result() if shell in docs_runs else run_one(shell)
    assert code == 0, f"{place}: `{shell}` exited {code}:\n{output}"


def test_every_fenced_block_says_what_it_is():
    """A block without an info string would be neither run here nor marked as not a command."""
    unmarked = [f"{_rel(path)}:{first}" for path in DOCS for info, first, _ in fenced_blocks(path) if not info]
    assert not unmarked, f"fenced blocks without an info string (bash, text, yaml, python): {unmarked}"


def test_the_docs_have_commands():
    places = {place.split(":")[0] for place, _ in ALL_COMMANDS}
    assert "README.md" in places and len(ALL_COMMANDS) >= 20, sorted(places)


def test_the_readme_runs_the_three_demos_setup_and_tests():
    readme = [command for place, command in ALL_COMMANDS if place.startswith("README.md:")]
    for command in (*SESSION_SCRIPTS, *THE_SUITE):
        assert command in readme, f"README.md's commands lack {command}"


BENCH = re.compile(r"`(bench/run [^`]*)`")


def bench_commands():
    found = []
    for path in DOCS:
        with open(path, encoding="utf-8") as stream:
            found += [(_rel(path), match) for match in BENCH.findall(stream.read())]
    return found


@pytest.mark.parametrize("place,command", bench_commands(), ids=[c for _, c in bench_commands()])
def test_bench_command_exists_with_its_options(place, command):
    words = command.split()
    if words[1:] == ["--help"]:
        return
    script = os.path.join(ROOT, "bench", words[1] + ".py")
    assert os.path.isfile(script), f"{place}: `{command}`: no bench/{words[1]}.py"
    with open(script, encoding="utf-8") as stream:
        source = stream.read()
    for word in words[2:]:
        if word.startswith("--"):
            assert f'"{word}"' in source, f"{place}: `{command}`: bench/{words[1]}.py declares no {word}"
