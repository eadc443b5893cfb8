"""A LeRobot dataset folder whose episodes are committed atomically.

LeRobot's v3.0 writer appends episodes to shared files (parquet files whose footer is only
written by ``finalize()``, videos concatenated in place, ``meta/info.json`` rewritten), so a
process killed in the middle of an episode could leave every earlier episode of those files
unreadable. Each episode is therefore written into a *version* of the dataset:

- ``DATASET`` is a symbolic link to ``.DATASET.versions/NNNNNN``, a complete LeRobot root
  that LeRobot's loader opens as it is (it follows the link);
- an episode is written into a staging copy (``.DATASET.versions/staging-PID-N``): ``meta/``
  copied, since LeRobot rewrites those files, ``data/`` and ``videos/`` hard-linked, since a
  LeRobot writer that reopens a dataset only ever starts new files there);
- ``commit`` renames the staging copy to the next version number and replaces the link
  (``os.replace``: atomic), then removes older versions.

A kill at any point leaves the link on a complete version; what the killed writer staged is
removed by the next ``DatasetStore`` on the same folder (its process is gone). A dataset
folder that is a plain directory (made elsewhere) is adopted as version 0.

Plain Python with no framework import: the LeRobot writer's venv uses it from this folder.
"""

import json
import os
import re
import shutil
import tempfile

__all__ = [
    "DatasetStore",
    "DatasetStoreError",
    "check_dataset_folder",
    "read_sidecar",
    "write_sidecar",
    "EPISODES_SIDECAR",
    "VERSIONS_SUFFIX",
]

VERSIONS_SUFFIX = ".versions"
# The framework's own per-episode record (task, outcome, frame counts and losses) beside
# LeRobot's metadata; LeRobot's loader ignores files it does not know.
EPISODES_SIDECAR = os.path.join("meta", "teleop_episodes.json")
_VERSION = re.compile(r"^\d{6}$")
_STAGING = re.compile(r"^staging-(\d+)-\d+$")
_COPIED = ("meta",)  # rewritten by LeRobot when it reopens a dataset: copied, never linked


class DatasetStoreError(RuntimeError):
    """The dataset folder cannot be used (the reason and the path in the text)."""


def read_sidecar(root: str) -> list:
    """The framework's record of each episode in the version ``root`` (empty before one)."""
    path = os.path.join(root, EPISODES_SIDECAR)
    if not os.path.exists(path):
        return []
    try:
        with open(path, encoding="utf-8") as stream:
            episodes = json.load(stream)
    except (OSError, ValueError) as exc:
        raise DatasetStoreError(f"{path}: unreadable episode list: {exc}") from None
    if not isinstance(episodes, list):
        raise DatasetStoreError(f"{path}: the episode list must be a JSON list")
    return episodes


def write_sidecar(root: str, episodes: list) -> None:
    """Write the episode record into a staging copy ``root`` (fsynced, then renamed)."""
    path = os.path.join(root, EPISODES_SIDECAR)
    temp = path + ".tmp"
    with open(temp, "w", encoding="utf-8") as stream:
        json.dump(episodes, stream, indent=1)
        stream.flush()
        os.fsync(stream.fileno())
    os.replace(temp, path)


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _fsync_dir(folder: str) -> None:
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def check_dataset_folder(path: str, min_free_mb: float) -> str | None:
    """Why episodes cannot be written to the dataset ``path`` (a folder that cannot be
    created or written, or less than ``min_free_mb`` free on its file system), or None when
    they can. Creates nothing: the nearest existing folder on the way is what is checked."""
    path = os.path.abspath(os.path.expanduser(path))
    if os.path.lexists(path) and not os.path.isdir(path):
        return f"dataset folder {path}: exists and is not a folder (nor a link to one)"
    existing = os.path.dirname(path)
    while not os.path.exists(existing):
        existing = os.path.dirname(existing)
    if not os.path.isdir(existing):
        return f"dataset folder {path}: cannot be created, {existing} is not a folder"
    try:
        with tempfile.NamedTemporaryFile(dir=existing, prefix=".write-check-"):
            pass
    except OSError as exc:
        return f"dataset folder {path}: {existing} is not writable ({exc.strerror})"
    free_mb = shutil.disk_usage(existing).free / 1e6
    if free_mb < min_free_mb:
        return (
            f"dataset folder {path}: only {free_mb:.0f} MB free on its disk, "
            f"at least {min_free_mb:.0f} MB needed (~min_free_mb)"
        )
    return None


class DatasetStore:
    """Versions of one dataset folder (see the module doc)."""

    def __init__(self, path: str):
        self.path = os.path.abspath(os.path.expanduser(path))
        parent, name = os.path.split(self.path)
        self.versions = os.path.join(parent, "." + name + VERSIONS_SUFFIX)
        self._staged = 0
        os.makedirs(self.versions, exist_ok=True)
        self._adopt_plain_folder()
        self.clean_stale()
        self._relink_if_missing()

    # -- reading ------------------------------------------------------------------------
    def _numbers(self) -> list[int]:
        return sorted(int(n) for n in os.listdir(self.versions) if _VERSION.match(n))

    def current(self) -> str | None:
        """The complete version the dataset link points at, or None before the first episode."""
        if not os.path.islink(self.path):
            return None
        target = os.path.realpath(self.path)
        return target if os.path.isdir(target) else None

    # -- repairs ------------------------------------------------------------------------
    def _adopt_plain_folder(self) -> None:
        if os.path.isdir(self.path) and not os.path.islink(self.path):
            if not os.path.isdir(os.path.join(self.path, "meta")):
                if os.listdir(self.path):
                    raise DatasetStoreError(f"{self.path}: a folder that is not a LeRobot dataset (no meta/)")
                os.rmdir(self.path)
                return
            number = (self._numbers() or [-1])[-1] + 1
            target = os.path.join(self.versions, f"{number:06d}")
            os.rename(self.path, target)
            self._link(target)

    def _relink_if_missing(self) -> None:
        numbers = self._numbers()
        if numbers and self.current() is None:
            self._link(os.path.join(self.versions, f"{numbers[-1]:06d}"))

    def clean_stale(self) -> list[str]:
        """Remove the staging copies whose writer process is gone; return them."""
        removed = []
        for name in os.listdir(self.versions):
            match = _STAGING.match(name)
            if match and int(match.group(1)) != os.getpid() and not _pid_alive(int(match.group(1))):
                shutil.rmtree(os.path.join(self.versions, name), ignore_errors=True)
                removed.append(name)
        return removed

    # -- writing ------------------------------------------------------------------------
    def stage(self) -> str:
        """A new staging root: a copy of the current version (meta copied, the rest
        hard-linked), or a path that does not exist yet before the first episode (LeRobot's
        ``create`` makes it)."""
        self._staged += 1
        staging = os.path.join(self.versions, f"staging-{os.getpid()}-{self._staged}")
        shutil.rmtree(staging, ignore_errors=True)
        current = self.current()
        if current is None:
            return staging
        os.makedirs(staging)
        for entry in os.listdir(current):
            source = os.path.join(current, entry)
            target = os.path.join(staging, entry)
            if entry in _COPIED or not os.path.isdir(source):
                if os.path.isdir(source):
                    shutil.copytree(source, target)
                else:
                    shutil.copy2(source, target)
            else:
                shutil.copytree(source, target, copy_function=os.link)
        return staging

    def commit(self, staging: str) -> str:
        """Make ``staging`` the current version (atomic); return its path."""
        if not os.path.isdir(os.path.join(staging, "meta")):
            raise DatasetStoreError(f"{staging}: not a LeRobot dataset root (no meta/), not committed")
        number = (self._numbers() or [-1])[-1] + 1
        target = os.path.join(self.versions, f"{number:06d}")
        os.rename(staging, target)
        _fsync_dir(self.versions)
        previous = self.current()
        self._link(target)
        if previous and previous != target:
            shutil.rmtree(previous, ignore_errors=True)
        return target

    def mark(self, index: int, success: bool) -> dict:
        """Set the success of saved episode ``index`` (a new version; LeRobot's files are
        untouched); return its record."""
        current = self.current()
        episodes = read_sidecar(current) if current else []
        if not 0 <= index < len(episodes):
            raise DatasetStoreError(f"episode {index} is not in {self.path} ({len(episodes)} episodes)")
        staging = self.stage()
        episodes[index]["success"] = bool(success)
        write_sidecar(staging, episodes)
        self.commit(staging)
        return episodes[index]

    def discard(self, staging: str) -> None:
        """Forget a staging copy."""
        shutil.rmtree(staging, ignore_errors=True)

    def _link(self, target: str) -> None:
        parent = os.path.dirname(self.path)
        temp = os.path.join(parent, f".{os.path.basename(self.path)}.link-{os.getpid()}")
        if os.path.lexists(temp):
            os.unlink(temp)
        os.symlink(os.path.relpath(target, parent), temp)
        os.replace(temp, self.path)
        _fsync_dir(parent)
