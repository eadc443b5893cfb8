"""The manual stays whole: docs/parameters.md indexes every YAML file under src/*/config and
no file that is gone, docs/README.md lists every page, and every relative link or image of
README.md and docs/*.md points at a file that exists."""

import glob
import os
import re

from ..conftest import ROOT

DOCS_DIR = os.path.join(ROOT, "docs")
PAGES = [os.path.join(ROOT, "README.md")] + sorted(glob.glob(os.path.join(DOCS_DIR, "*.md")))


def _read(path):
    with open(path, encoding="utf-8") as stream:
        return stream.read()


def test_parameter_index_lists_every_yaml_file():
    index = _read(os.path.join(DOCS_DIR, "parameters.md"))
    shipped = sorted(
        os.path.relpath(path, ROOT)
        for path in glob.glob(os.path.join(ROOT, "src", "*", "config", "**", "*.yaml"), recursive=True)
    )
    assert shipped, "no YAML files found under src/*/config"
    listed = set(re.findall(r"^\| `(src/[^`]+\.yaml)` \|", index, flags=re.MULTILINE))
    missing = [path for path in shipped if path not in listed]
    assert not missing, (
        f"docs/parameters.md does not index {missing}: add a row (what it configures, which node loads it)"
    )
    gone = sorted(listed - set(shipped))
    assert not gone, f"docs/parameters.md indexes files that do not exist: {gone}"


def test_parameter_index_points_to_the_generated_interfaces():
    assert "(interfaces.md)" in _read(os.path.join(DOCS_DIR, "parameters.md"))


def test_table_of_contents_lists_every_page():
    contents = _read(os.path.join(DOCS_DIR, "README.md"))
    pages = [os.path.basename(path) for path in PAGES[1:] if not path.endswith(os.sep + "README.md")]
    missing = [page for page in pages if f"]({page})" not in contents]
    assert not missing, f"docs/README.md does not list {missing}"


LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def test_relative_links_and_images_exist():
    broken = []
    for page in PAGES:
        for target in LINK.findall(_read(page)):
            if re.match(r"[a-z]+:", target) or target.startswith("#"):
                continue
            path = os.path.normpath(os.path.join(os.path.dirname(page), target.split("#")[0]))
            if not os.path.exists(path):
                broken.append(f"{os.path.relpath(page, ROOT)}: {target}")
    assert not broken, f"links to missing files: {broken}"


def test_readme_stays_short():
    lines = _read(os.path.join(ROOT, "README.md")).count("\n")
    assert lines <= 200, f"README.md has {lines} lines: move detail into docs/"
