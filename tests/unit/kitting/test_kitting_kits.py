"""Kits (kitting.kits): kit order files checked before anything runs, the seeded feed, and
ARIAC's kitting score on hand-made trays."""

import pytest

from kitting.cell import load_cell
from kitting.kits import Kit, KitOrderError, default_kits, kit_feed, kit_summary, load_kit_order, score_kit
from kitting.parts import CLASS_NAMES


@pytest.fixture(scope="module")
def cell():
    return load_cell()


def test_default_kits_are_one_of_each_class_and_a_partial_last_kit():
    kits = default_kits(14)
    assert [len(k.classes) for k in kits] == [6, 6, 2]
    assert kits[0].classes == tuple(CLASS_NAMES) and kits[2].classes == tuple(CLASS_NAMES[:2])


def test_kit_feed_shuffles_inside_each_kit_reproducibly():
    kits = default_kits(18)
    feed = kit_feed(kits, seed=4)
    assert feed == kit_feed(kits, seed=4) and feed != kit_feed(kits, seed=5)
    for index in range(3):
        assert sorted(c for k, c in feed if k == index) == sorted(CLASS_NAMES)
    assert [k for k, _ in feed] == sorted(k for k, _ in feed)  # kit after kit
    assert len(kit_feed(kits, seed=4, parts=7)) == 7


def test_the_example_kit_order_loads(cell):
    kits = load_kit_order(cell.source.replace("cell.yaml", "kit_order_example.yaml"), cell)
    assert [k.classes for k in kits][:2] == [
        ("bolt_yellow", "nut_yellow", "washer_yellow"),
        ("bolt_silver", "nut_silver", "washer_silver"),
    ]


@pytest.mark.parametrize(
    "text, message",
    [
        ("kits: [[bolt_yellow, bolt_gold]]", "kit 1: unknown part class 'bolt_gold'"),
        ("kits: [[nut_yellow], [nut_silver, nut_silver]]", "kit 2: ['nut_silver'] more than once (one part per slot)"),
        ("kits: [[]]", "kit 1: must be a non-empty list"),
        ("kits: []", "non-empty list of kits"),
        ("kit: [[nut_yellow]]", "needs a 'kits' list"),
        ("kits: [[nut_yellow]]\nrepeat: 0", "repeat must be a whole number"),
        ("kits: [[nut_yellow]]\ncolour: red", "unknown key(s) ['colour']"),
        ("kits: [[nut_yellow", "not valid YAML"),
    ],
)
def test_a_bad_kit_order_is_refused_naming_the_file_and_the_kit(cell, tmp_path, text, message):
    path = tmp_path / "order.yaml"
    path.write_text(text)
    with pytest.raises(KitOrderError) as error:
        load_kit_order(str(path), cell)
    assert str(path) in str(error.value) and message in str(error.value)


def test_a_missing_kit_order_file_is_refused(cell, tmp_path):
    with pytest.raises(KitOrderError, match="cannot read"):
        load_kit_order(str(tmp_path / "none.yaml"), cell)


KIT = Kit(0, ("bolt_yellow", "nut_yellow", "washer_silver"))


def test_a_complete_kit_scores_the_maximum():
    score = score_kit(
        KIT, [("bolt_yellow", "bolt_yellow"), ("nut_yellow", "nut_yellow"), ("washer_silver", "washer_silver")]
    )
    assert score.slot_points == {"bolt_yellow": 3, "nut_yellow": 3, "washer_silver": 3}
    assert (score.bonus, score.penalty, score.score, score.max_score, score.complete) == (3, 0, 12, 12, True)


def test_a_missing_part_loses_its_slot_and_the_bonus():
    score = score_kit(KIT, [("bolt_yellow", "bolt_yellow"), ("nut_yellow", "nut_yellow")])
    assert (score.slot_points["washer_silver"], score.bonus, score.score, score.complete) == (0, 0, 6, False)


def test_the_right_type_in_the_wrong_colour_scores_two_and_a_wrong_type_none():
    tray = [("nut_silver", "nut_yellow"), ("washer_yellow", "bolt_yellow"), ("washer_silver", "washer_silver")]
    score = score_kit(KIT, tray)
    assert score.slot_points == {"bolt_yellow": 0, "nut_yellow": 2, "washer_silver": 3}
    assert (score.bonus, score.score) == (0, 5)


def test_extra_parts_are_penalised_and_withhold_completion_but_the_score_is_never_negative():
    full = [("bolt_yellow", "bolt_yellow"), ("nut_yellow", "nut_yellow"), ("washer_silver", "washer_silver")]
    extra = score_kit(KIT, full + [("nut_silver", "nut_silver"), ("bolt_yellow", "bolt_yellow")])
    assert (extra.bonus, extra.penalty, extra.score, extra.complete) == (3, 2, 10, False)
    junk = score_kit(Kit(1, ("bolt_yellow",)), [("nut_silver", "nut_silver")] * 4)
    assert junk.score == 0 and junk.penalty == 3


def test_kit_summary_adds_the_kits_up():
    full = [("bolt_yellow", "bolt_yellow"), ("nut_yellow", "nut_yellow"), ("washer_silver", "washer_silver")]
    summary = kit_summary([score_kit(KIT, full), score_kit(KIT, full[:2])])
    assert summary["kits"] == 2 and summary["kits_complete"] == 1
    assert summary["kit_score"] == 18 and summary["kit_score_max"] == 24 and summary["kit_score_rate"] == 0.75
