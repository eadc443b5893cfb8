"""The speed ratio typed on the page: refusals name the accepted range (never a Python
exception's text) and a large increase asks for confirmation."""

import pytest

from dashboard.controls import CONFIRM_FACTOR, check_speed_ratio
from motion_commander.config import TELEOP_PARAMETERS

PARAM = TELEOP_PARAMETERS.params["speed_ratio"]


def check(text, current=1.0):
    return check_speed_ratio(text, current, PARAM.low, PARAM.high, PARAM.low_open)


@pytest.mark.parametrize("text", ["abc", "", "   ", None, "nan", "inf", "-inf", "1,5", "0", "-1", "10.5", "1e9"])
def test_invalid_input_is_refused_with_the_accepted_range(text):
    decision = check(text)
    assert not decision.ok and decision.value is None
    assert "more than 0 and up to 10" in decision.message
    for leak in ("float()", "NoneType", "ValueError", "Traceback", "argument"):
        assert leak not in decision.message


def test_messages_say_what_was_wrong():
    assert "not a number" in check("abc").message and "'abc'" in check("abc").message
    assert "enter a speed ratio" in check("").message
    assert "not a finite number" in check("nan").message
    assert "out of range" in check("12").message


@pytest.mark.parametrize("text, value", [("0.5", 0.5), (" 1.25 ", 1.25), ("2", 2.0), (1.5, 1.5), ("10", 10.0)])
def test_valid_ratios_within_twice_the_current_one_pass(text, value):
    decision = check(text, current=5.0)
    assert decision.ok and decision.value == value and not decision.confirm


def test_more_than_twice_the_current_ratio_needs_confirmation():
    decision = check("2.5", current=1.0)
    assert decision.ok and decision.confirm and decision.value == 2.5
    assert "1.00" in decision.message and "2.50" in decision.message
    assert not check(str(CONFIRM_FACTOR), current=1.0).confirm  # exactly 2x: no question


def test_lowering_the_ratio_never_asks_and_an_unknown_current_ratio_never_asks():
    assert not check("0.1", current=5.0).confirm
    assert not check("9", current=None).confirm


def test_a_closed_lower_bound_accepts_the_bound_itself():
    assert check_speed_ratio("0", None, 0.0, 1.0, low_open=False).ok
    assert "from 0 to 1" in check_speed_ratio("2", None, 0.0, 1.0).message
