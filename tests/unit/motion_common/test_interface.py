"""motion_common.interface: declarations, name resolution and the comparison with a running
graph (the master's getSystemState answer), without a roscore."""

import pytest

from motion_common.interface import NodeInterface, Service, Topic, graph_mismatches, resolve
from motion_common.params import Param, ParamSchema

NODE = NodeInterface(
    "pkg",
    "talker",
    "a test node",
    ParamSchema([Param("rate", 1.0, "Hz", low=0)]),
    publishes=(Topic("chatter", "std_msgs/String"), Topic("~debug", "std_msgs/String", optional=True)),
    subscribes=(Topic("~input", "std_msgs/String"),),
    serves=(Service("reset", "std_srvs/Trigger"),),
)


def state(pubs=(), subs=(), srvs=()):
    return (
        [[name, ["/left/talker"]] for name in pubs],
        [[name, ["/left/talker"]] for name in subs],
        [[name, ["/left/talker"]] for name in srvs],
    )


def test_resolve_follows_rospy():
    assert resolve("chatter", "/left", "/left/talker") == "/left/chatter"
    assert resolve("chatter", "/", "/talker") == "/chatter"
    assert resolve("~input", "/left", "/left/talker") == "/left/talker/input"
    assert resolve("/abs", "/left", "/left/talker") == "/abs"


def test_a_node_that_matches_its_declaration_passes():
    graph = state(["/left/chatter", "/rosout"], ["/left/hand"], ["/left/reset", "/left/talker/get_loggers"])
    assert graph_mismatches(NODE, "/left/talker", graph, {"~input": "hand"}) == []


def test_an_undeclared_topic_and_a_missing_one_are_both_named():
    graph = state(["/left/chatter", "/left/extra"], [], ["/left/reset"])
    problems = graph_mismatches(NODE, "/left/talker", graph)
    assert any("/left/extra" in p and "does not declare" in p for p in problems)
    assert any("/left/talker/input" in p and "declares" in p for p in problems)


def test_optional_entries_may_be_absent_but_never_undeclared():
    graph = state(["/left/chatter", "/left/talker/debug"], ["/left/talker/input"], ["/left/reset"])
    assert graph_mismatches(NODE, "/left/talker", graph) == []


def test_markdown_lists_every_entry_and_parameter():
    text = NODE.markdown()
    for needle in ("`chatter`", "`~debug`", "(optional)", "`~input`", "`reset`", "`rate`", "Hz"):
        assert needle in text


def test_service_names_must_be_relative():
    with pytest.raises(ValueError, match="relative"):
        Service("/motion_controller", "motion_commander/commander")
