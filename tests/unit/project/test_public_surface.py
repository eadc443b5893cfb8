"""Every package's public surface: ``import <package>`` stays cheap, every name in its
``__all__`` resolves, and its docstring names every module it has.

A package re-exports its public names lazily (a module-level ``__getattr__``, PEP 562), so
a node or a test that needs one light module does not pay for pybullet, cv2, mediapipe,
onnxruntime, pinocchio or rospy. Each import runs in a fresh interpreter: this process has
most of them loaded already. Packages are imported two ways: from the source tree, as this
suite does, and through the catkin workspace's devel space, as the nodes do (there the
package is a generated shim that runs the source ``__init__.py`` and adds ``msg``/``srv``).
"""

import ast
import json
import os
import subprocess
import sys
import textwrap

import pytest

from ..conftest import ROOT

SRC = os.path.join(ROOT, "src")
DEVEL = os.path.join(ROOT, "catkin_ws", "devel", "lib", "python3", "dist-packages")
HEAVY = ("pybullet", "cv2", "mediapipe", "onnxruntime", "pinocchio", "rospy")


def python_packages():
    """(dotted name, folder) of every Python package under src/<catkin package>/<same name>/."""
    found = []
    for catkin_package in sorted(os.listdir(SRC)):
        top = os.path.join(SRC, catkin_package, catkin_package)
        for folder, dirs, files in os.walk(top):
            dirs[:] = sorted(d for d in dirs if d != "__pycache__")
            if "__init__.py" in files:
                relative = os.path.relpath(folder, top)
                found.append(
                    (catkin_package if relative == "." else ".".join([catkin_package] + relative.split(os.sep)), folder)
                )
    return found


PACKAGES = python_packages()
NAMES = [name for name, _ in PACKAGES]


def search_path(mode):
    """sys.path entries that come first: the source tree, or the devel space before it."""
    sources = [os.path.join(SRC, name) for name in sorted({n.split(".")[0] for n in NAMES})]
    return sources if mode == "source" else [DEVEL] + sources


def workspace_built(package):
    return os.path.isfile(os.path.join(DEVEL, package.split(".")[0], "__init__.py"))


def run_fresh(mode, code):
    """Runs ``code`` in a fresh interpreter with ``search_path(mode)`` first; its JSON output."""
    prologue = f"import json, sys\nsys.path[:0] = {search_path(mode)!r}\n"
    done = subprocess.run(
        [sys.executable, "-c", prologue + textwrap.dedent(code)], cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_every_package_is_found():
    assert {
        "motion_common",
        "motion_sensor",
        "motion_commander",
        "hw_interface",
        "hw_interface.testing",
        "motion_apps",
        "kitting",
        "dashboard",
    } <= set(NAMES)


@pytest.mark.parametrize("mode", ["source", "workspace"])
@pytest.mark.parametrize("package", NAMES)
def test_importing_the_package_loads_no_heavy_module(package, mode):
    if mode == "workspace" and not workspace_built(package):
        pytest.skip("the catkin workspace is not built (scripts/setup builds it)")
    loaded = run_fresh(
        mode,
        f"""
        import importlib
        package = importlib.import_module({package!r})
        heavy = sorted(m for m in sys.modules if m.split(".")[0] in {HEAVY!r})
        print(json.dumps({{"heavy": heavy, "all": list(package.__all__), "file": package.__file__}}))
        """,
    )
    assert loaded["heavy"] == [], f"import {package} loaded {loaded['heavy']}"
    assert loaded["all"], f"{package} has an empty __all__"
    if mode == "workspace" and "." not in package:
        assert loaded["file"].startswith(DEVEL)  # the shim, not the source file


@pytest.mark.parametrize("package", NAMES)
def test_every_public_name_resolves(package):
    # Through the devel space when it is built: the ROS edges need the generated messages.
    mode = "workspace" if workspace_built(package) else "source"
    results = run_fresh(
        mode,
        f"""
        import importlib
        import importlib.util
        package = importlib.import_module({package!r})
        results = {{}}
        for name in package.__all__:
            module_name = {package!r} + "." + package._PUBLIC[name]
            try:
                value = getattr(package, name)
                defined = getattr(importlib.import_module(module_name), name)
                if value is not defined:
                    results[name] = f"is not {{module_name}}.{{name}}"
                elif importlib.util.find_spec({package!r} + "." + name) is not None:
                    results[name] = "is also a submodule's name: importing it would hide the name"
                else:
                    results[name] = "ok"
            except ModuleNotFoundError as error:
                missing = error.name or ""
                generated = missing.endswith((".msg", ".srv")) or missing.split(".")[0].endswith("_msgs")
                results[name] = "needs messages: " + missing if generated else f"{{type(error).__name__}}: {{error}}"
            except Exception as error:
                results[name] = f"{{type(error).__name__}}: {{error}}"
        results["<dir>"] = "ok" if set(package.__all__) <= set(dir(package)) else "dir() misses names"
        results["<unknown>"] = "ok" if not hasattr(package, "no_such_public_name") else "unknown name resolves"
        print(json.dumps(results))
        """,
    )
    need_messages = sorted(name for name, result in results.items() if result.startswith("needs messages"))
    broken = {name: result for name, result in results.items() if result != "ok" and name not in need_messages}
    assert broken == {}, "\n".join(f"{package}.{name}: {result}" for name, result in broken.items())
    if need_messages:
        assert mode == "source", f"{need_messages} need messages the built workspace should have"
        pytest.skip(f"not resolved without the built workspace's messages: {need_messages}")


@pytest.mark.parametrize("package, folder", PACKAGES, ids=NAMES)
def test_the_docstring_names_every_module(package, folder):
    with open(os.path.join(folder, "__init__.py"), encoding="utf-8") as stream:
        docstring = ast.get_docstring(ast.parse(stream.read())) or ""
    modules = sorted(name[:-3] for name in os.listdir(folder) if name.endswith(".py") and name != "__init__.py")
    modules += sorted(name for name in os.listdir(folder) if os.path.isfile(os.path.join(folder, name, "__init__.py")))
    missing = [name for name in modules if f"``{name}``" not in docstring]
    assert missing == [], f"{package}'s docstring does not name {missing}: say what each is for"
