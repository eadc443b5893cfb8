"""Which application the session runs (teleop, teach or kitting) and so which panels the
page shows. The launch file says it (``~application``); a dashboard started on its own next
to a session leaves it empty and the running graph decides (which topics are published).
Plain Python.
"""

__all__ = ["APPLICATIONS", "PANELS", "detect_application", "panels_for"]

APPLICATIONS = ("teleop", "teach", "kitting")

# Panels every application shows: the robot, its path, the charts, the log, the joints,
# the recorded episodes.
_COMMON = ("scene", "path", "joints", "series", "events", "robot", "episodes")
PANELS = {
    "teleop": frozenset(_COMMON + ("input", "teleop", "sequencer", "programs")),
    "teach": frozenset(_COMMON + ("input", "teleop", "sequencer", "programs")),
    "kitting": frozenset(_COMMON + ("camera", "kitting")),
}

# A topic that only that application's nodes publish -> the application (first match wins).
_SIGNATURES = (
    ("kitting/object_poses", "kitting"),
    ("kitting/events", "kitting"),
    ("teach/feedback", "teach"),
)


def detect_application(published_topics) -> str:
    """The application from the names of the published topics (absolute or relative):
    kitting when the kitting cell publishes, teach when teach mode does, else teleop."""
    names = {str(name).lstrip("/") for name in published_topics}
    for topic, application in _SIGNATURES:
        if topic in names:
            return application
    return "teleop"


def panels_for(application: str) -> frozenset:
    """The panels of ``application``; an unknown name is a programming error (ValueError)."""
    try:
        return PANELS[application]
    except KeyError:
        raise ValueError(f"unknown application {application!r} (one of {', '.join(APPLICATIONS)})") from None
