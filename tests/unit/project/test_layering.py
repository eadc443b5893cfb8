"""The one-way layering rule, enforced by parsing every import of the framework's code.

Layers, lowest first (docs/architecture.md, "Layers"):
  motion_common                 imports none of the framework's packages
  motion_sensor, hw_interface   import motion_common only, never each other
  motion_commander (the core)   may import the three above
  application packages          may import all of the above; nothing imports them
Generated messages and services (``<package>.msg``, ``<package>.srv``) may cross in any
direction. Test doubles live in ``<package>.testing`` modules and are injected (by the
driver registry's names), never imported by production code.
"""

import ast
import os

import pytest

from ..conftest import ROOT

SRC = os.path.join(ROOT, "src")

# package -> framework packages whose Python modules it may import.
ALLOWED = {
    "motion_common": set(),
    "motion_sensor": {"motion_common"},
    "hw_interface": {"motion_common"},
    "motion_commander": {"motion_common", "motion_sensor", "hw_interface"},
}
# Application packages (teach, vision, kitting, dashboard) go here as they arrive: they
# may import everything in ALLOWED, and no package may import them.
# The dashboard is one too: it reaches the other applications through their topics and
# commands (run_program, kitting_trials), never by importing them.
APPLICATIONS = {"motion_apps", "kitting", "dashboard"}


# Packages with no Python at all (launch files only), so no layer to keep.
NO_PYTHON = {"motion_bringup"}


def framework_packages():
    """Every catkin package under src/ (a folder with a package.xml) that holds Python."""
    return sorted(
        name
        for name in os.listdir(SRC)
        if os.path.isfile(os.path.join(SRC, name, "package.xml")) and name not in NO_PYTHON
    )


def test_bringup_holds_no_python():
    for package in NO_PYTHON:
        for _folder, _, files in os.walk(os.path.join(SRC, package)):
            assert not [f for f in files if f.endswith(".py")], f"{package} is launch files only"


def python_files(package):
    """The package's Python module files and its node executables."""
    base = os.path.join(SRC, package)
    for folder, _, files in os.walk(base):
        for name in files:
            path = os.path.join(folder, name)
            in_nodes = os.path.basename(folder) in ("nodes", "scripts")
            if name.endswith(".py") or in_nodes:
                with open(path, "rb") as stream:
                    head = stream.read(64)
                if name.endswith(".py") or head.startswith(b"#!") and b"python" in head:
                    yield path


def module_parts(path):
    """Dotted package path of a module file under src/<pkg>/<pkg>/ (e.g. [hw_interface, testing])."""
    relative = os.path.relpath(os.path.dirname(path), SRC).split(os.sep)
    return relative[1:] if len(relative) > 1 else []


def imported_modules(path):
    """Absolute module names imported by a file; relative imports are resolved."""
    with open(path, encoding="utf-8") as stream:
        tree = ast.parse(stream.read(), path)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0:
                yield node.module
                continue
            base = module_parts(path)
            base = base[: len(base) - (node.level - 1)] if node.level > 1 else base
            names = [node.module] if node.module else [alias.name for alias in node.names]
            for name in names:
                yield ".".join(base + [name])


def violations(package, path, known):
    """(file, module, reason) for every import of ``path`` that breaks the rule."""
    allowed = ALLOWED.get(package, set(ALLOWED) if package in APPLICATIONS else set())
    found = []
    for module in imported_modules(path):
        parts = module.split(".")
        top = parts[0]
        if top not in known or top == package:
            if "testing" in parts[1:] and "testing" not in path.split(os.sep):
                found.append((path, module, "production code imports a test double; inject it instead"))
            continue
        if len(parts) > 1 and parts[1] in ("msg", "srv"):
            continue  # generated messages may cross layers
        if top in APPLICATIONS:
            found.append((path, module, "nothing may import an application package"))
        elif top not in allowed:
            found.append((path, module, f"{package} may import only {sorted(allowed) or 'none of ours'}"))
        elif "testing" in parts[1:]:
            found.append((path, module, "production code imports a test double; inject it instead"))
    return found


def test_every_package_has_a_layer():
    unknown = [p for p in framework_packages() if p not in ALLOWED and p not in APPLICATIONS]
    assert unknown == [], f"add {unknown} to ALLOWED or APPLICATIONS in this test (and to docs/architecture.md)"


@pytest.mark.parametrize("package", framework_packages())
def test_imports_go_one_way(package):
    known = set(framework_packages())
    files = list(python_files(package))
    assert files, f"no Python files found in {package}"
    broken = [v for path in files for v in violations(package, path, known)]
    assert broken == [], "\n".join(f"{os.path.relpath(p, ROOT)}: imports {m}: {why}" for p, m, why in broken)


def test_the_checker_catches_an_upward_import(tmp_path):
    fake = tmp_path / "driver.py"
    fake.write_text("import os\nfrom motion_commander.teleop import TeleopMapper\nfrom motion_commander.srv import x\n")
    found = violations("hw_interface", str(fake), set(ALLOWED))
    assert [m for _, m, _ in found] == ["motion_commander.teleop"]


def test_the_checker_catches_a_test_double_in_production(tmp_path):
    fake = tmp_path / "driver.py"
    fake.write_text("from hw_interface.testing.fake_rtde import FakeUR\n")
    assert violations("hw_interface", str(fake), set(ALLOWED))


def test_relative_imports_are_resolved():
    path = os.path.join(SRC, "hw_interface", "hw_interface", "driver.py")
    assert module_parts(path) == ["hw_interface"]
    tree_file = os.path.join(SRC, "hw_interface", "hw_interface", "testing", "fake.py")
    assert module_parts(tree_file) == ["hw_interface", "testing"]
