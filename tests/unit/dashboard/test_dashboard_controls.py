"""The dashboard's control rules (what is disabled, and the reason shown) and its access rule."""

import pytest

from dashboard.access import check_access_config, token_accepted
from dashboard.controls import control_states
from motion_common.errors import ParameterError

RUNNING = {
    "status": 2,
    "engage_mode": "auto",
    "stop_latched": False,
    "server_up": True,
    "speed_ratio": 1.0,
    "filter": "mean",
    "kitting_cell": False,
}


def states(**changes):
    values = dict(RUNNING, **{k: v for k, v in changes.items() if k in RUNNING or k in ("status",)})
    jobs = {k: v for k, v in changes.items() if k in ("program_job", "campaign_job", "selected_program")}
    return control_states(values, **jobs)


def test_stop_is_never_disabled():
    for values in ({}, RUNNING, dict(RUNNING, stop_latched=True)):
        assert control_states(values, program_job=True, campaign_job=True)["stop"].enabled


def test_release_only_when_latched():
    assert not states()["release"].enabled and "not latched" in states()["release"].reason
    assert states(stop_latched=True)["release"].enabled


def test_replay_disabled_while_teleop_is_engaged_with_the_reason():
    replay = states(selected_program="pick")["replay"]
    assert not replay.enabled and "teleop is engaged" in replay.reason
    assert states(selected_program="pick", status=1)["replay"].enabled
    assert states(selected_program="pick", status=12)["replay"].reason.startswith("teleop is engaged")


@pytest.mark.parametrize(
    "change, words",
    [
        ({}, "select a program"),
        ({"selected_program": "p", "status": 1, "stop_latched": True}, "latched"),
        ({"selected_program": "p", "status": 1, "server_up": False}, "no robot server"),
        ({"selected_program": "p", "status": 1, "program_job": True}, "in progress"),
        ({"selected_program": "p", "status": 1, "campaign_job": True}, "campaign"),
    ],
)
def test_replay_reasons(change, words):
    replay = states(**change)["replay"]
    assert not replay.enabled and words in replay.reason


def test_dry_run_needs_no_server_and_no_disengage():
    assert states(selected_program="p", server_up=False)["dry_run"].enabled
    assert not states(selected_program="p", program_job=True)["dry_run"].enabled


def test_engage_controls_only_in_button_mode():
    auto = states(status=1)
    assert not auto["engage"].enabled and "engage:=button" in auto["engage"].reason
    button = states(status=1, engage_mode="button")
    assert button["engage"].enabled and not button["disengage"].enabled
    engaged = states(status=2, engage_mode="button")
    assert engaged["disengage"].enabled and not engaged["engage"].enabled
    assert "Release" in states(status=11, engage_mode="button", stop_latched=True)["engage"].reason
    assert "not running" in control_states({})["engage"].reason


def test_settings_need_their_nodes():
    assert states()["speed_ratio"].enabled and states()["filter"].enabled
    assert "motion_commander" in control_states({})["speed_ratio"].reason
    assert "sequencer" in control_states({})["filter"].reason


def test_campaign_controls():
    assert "kitting_sim" in states()["campaign_start"].reason
    assert states(kitting_cell=True, status=1)["campaign_start"].enabled
    assert not states(kitting_cell=True, campaign_job=True)["campaign_start"].enabled
    assert states(campaign_job=True)["campaign_end"].enabled and not states()["campaign_end"].enabled


def test_local_host_needs_no_token_but_the_network_does():
    check_access_config("127.0.0.1", "")
    check_access_config("localhost", "")
    with pytest.raises(ParameterError, match="dashboard_token"):
        check_access_config("0.0.0.0", "")
    with pytest.raises(ParameterError, match="too weak"):
        check_access_config("0.0.0.0", "short")
    check_access_config("0.0.0.0", "0123456789abcdef")


def test_token_check():
    assert token_accepted("", "")
    assert token_accepted("0123456789abcdef", "0123456789abcdef")
    assert not token_accepted("0123456789abcdef", "")
    assert not token_accepted("0123456789abcdef", "0123456789abcdeX")


def test_tray_swapped_needs_a_filled_tray_and_no_campaign():
    assert "kitting node" in states()["tray_swapped"].reason
    empty = {"slots": ["bolt_silver"], "filled": [], "complete": False}
    full = {"slots": ["bolt_silver"], "filled": ["bolt_silver"], "complete": True}
    assert "empty" in control_states(dict(RUNNING, tray=empty))["tray_swapped"].reason
    assert control_states(dict(RUNNING, tray=full))["tray_swapped"].enabled
    assert "itself" in control_states(dict(RUNNING, tray=full), campaign_job=True)["tray_swapped"].reason


def test_tray_swapped_waits_for_a_campaign_the_page_did_not_start():
    full = {"slots": ["bolt_silver"], "filled": ["bolt_silver"], "complete": True}
    running = dict(RUNNING, tray=full, campaign_progress={"done": 2, "trials": 6})
    assert "itself" in control_states(running)["tray_swapped"].reason
    assert control_states(dict(running, campaign_result={"successes": 6}))["tray_swapped"].enabled
    assert control_states(dict(running, campaign_progress={"done": 6, "trials": 6}))["tray_swapped"].enabled
