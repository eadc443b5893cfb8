"""The pure-Python suite, one folder per package under test (``project/``: checks across
packages).

The folders are Python packages so that pytest names each test module by its path
(``unit.kitting.test_vision``): two folders may hold test files of the same name. A folder
must never be imported as a top-level package (``tests/unit`` is not put on ``sys.path``),
since each is named after the framework package it tests. Shared fixtures are in
``conftest.py``; test modules import its constants and ``stop_helpers`` relatively
(``from ..conftest import ROOT``).
"""
