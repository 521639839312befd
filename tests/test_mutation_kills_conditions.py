"""The protocol's conditions (protocol/conditions.py) where mutation testing found the suite silent
(docs/testing.md): how a shift is parsed and refused, the factors of a condition, the suites of one task (the
shifted ones drawn at seed + 1 from the held-out split, a family's own condition among factor shifts, a
condition listed twice), the fingerprint's payload, and a family condition's checks and environments."""

from __future__ import annotations

import hashlib
import json
import re

import pytest

from lerobot_factorworld.families import condition_family, family_of
from lerobot_factorworld.protocol import conditions
from lerobot_factorworld.protocol.sampling import SamplingOptions, sample_configs, shift_configs

PICK_CONDITIONS = ("held_out_phrasings", "held_out_objects")


def test_a_shift_is_one_factor_a_pair_or_a_familys_condition():
    assert conditions.parse_shift("camera_pos") == ("camera_pos",)
    assert conditions.parse_shift(" light + distractors ") == ("light", "distractors")
    assert conditions.parse_shift("light++camera_pos") == ("light", "camera_pos")
    assert conditions.parse_shift("held_out_objects") == ("held_out_objects",)
    message = "a shift names one factor or a pair of distinct factors joined by '+', got {!r}"
    for shift in ("light+light", "light+camera_pos+table_pos", " + "):
        with pytest.raises(ValueError, match=f"^{re.escape(message.format(shift))}$"):
            conditions.parse_shift(shift)
    with pytest.raises(ValueError, match="fog"):
        conditions.parse_shift("light+fog")
    with pytest.raises(ValueError, match="held_out_objects"):  # a family's condition stands alone
        conditions.parse_shift("held_out_objects+light")


def test_the_factors_and_name_of_a_condition():
    assert conditions.shifted_factors("train") == ()
    assert conditions.shifted_factors("light+camera_pos") == ("light", "camera_pos")
    assert conditions.shifted_factors("held_out_phrasings") == ("held_out_phrasings",)
    assert conditions.condition_name(("light", "camera_pos")) == "light+camera_pos"
    assert conditions.family_conditions() == PICK_CONDITIONS
    assert conditions.is_family_condition("held_out_phrasings") and not conditions.is_family_condition("light")


def test_the_suites_of_a_task_draw_shifts_at_seed_plus_one_from_the_held_out_split():
    options = SamplingOptions(widths={"camera_pos": "wide"})
    train = sample_configs("door-open", 2, 7, "train", ["light", "camera_pos"], options)
    suites = conditions.evaluation_suites(
        "door-open", 2, ["light", "camera_pos"], ["light", "camera_pos+light"], 3, 7, options
    )
    assert list(suites) == ["train", "light", "camera_pos+light"]
    assert suites["train"] == train
    assert suites["light"] == shift_configs(train, ("light",), 3, 8, "eval", options)
    assert suites["camera_pos+light"] == shift_configs(train, ("camera_pos", "light"), 3, 8, "eval", options)
    assert [c.split for c in suites["light"]] == ["eval"] * 3
    # given training environments are used as they are
    given = sample_configs("door-open", 1, 3, "train", ["table_texture"])
    again = conditions.evaluation_suites("door-open", 9, ["light"], ["table_texture"], 2, 7, train_configs=given)
    assert again == {"train": given, "table_texture": shift_configs(given, ("table_texture",), 2, 8, "eval")}
    assert conditions.evaluation_suites("door-open", 1, ["light"], ["light"], 1) == conditions.evaluation_suites(
        "door-open", 1, ["light"], ["light"], 1, 0
    )  # seed 0 by default
    with pytest.raises(ValueError, match=r"^condition 'light' is listed twice$"):
        conditions.evaluation_suites("door-open", 1, ["light"], ["light", " light"], 1, 0)


def test_a_familys_condition_among_the_shifts():
    train = sample_configs("pick", 2, 5, "train", ["light"])
    suites = conditions.evaluation_suites(
        "pick", 2, ["light"], ["held_out_objects", "light"], 4, 5, train_configs=train
    )
    assert list(suites) == ["train", "held_out_objects", "light"]
    pick = condition_family("held_out_objects")
    assert suites["held_out_objects"] == pick.condition_configs(train, "held_out_objects", 4, 6)
    assert suites["light"] == shift_configs(train, ("light",), 4, 6, "eval")
    assert conditions.condition_configs(train, "held_out_objects", 4, 6) == suites["held_out_objects"]
    assert conditions.condition_configs(train, "held_out_phrasings", 3, 2, pick) == pick.condition_configs(
        train, "held_out_phrasings", 3, 2
    )


def test_the_fingerprint_hashes_the_configs_and_the_object_width():
    configs = sample_configs("door-open", 2, 1, "train", ["light"])

    def expected(width: str) -> str:
        payload = {"configs": [c.to_dict() for c in configs], "object_pos_width": width}
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]

    assert conditions.fingerprint(configs) == expected("default") == conditions.fingerprint(configs, "default")
    assert conditions.fingerprint(configs, "wide") == expected("wide")
    assert conditions.fingerprint(configs[:1]) != conditions.fingerprint(configs)


def test_a_family_condition_is_checked_against_the_tasks():
    conditions.check_condition("held_out_phrasings", ["pick"])
    with pytest.raises(
        ValueError, match=r"^unknown condition 'light'; family conditions: held_out_phrasings, held_out_objects$"
    ):
        conditions.check_condition("light", ["pick"])
    with pytest.raises(ValueError, match=r"not to door-open$"):
        conditions.check_condition("held_out_objects", ["pick", "door-open"])


def test_a_conditions_family_is_the_given_one_then_the_conditions_then_the_tasks():
    door = sample_configs("door-open", 1, 0, "train", ["light"])
    with pytest.raises(ValueError, match=r"^unknown condition 'light'; valid: none$"):  # door-open's family
        conditions.condition_configs(door, "light", 1, 0)
    with pytest.raises(ValueError, match=r"applies to the pick family only .*, not to door-open$"):  # the condition's
        conditions.condition_configs(door, "held_out_objects", 1, 0)
    pick = sample_configs("pick", 1, 0, "train", ["light"])
    with pytest.raises(ValueError, match=r"^unknown condition 'held_out_objects'; valid: none$"):  # the given one
        conditions.condition_configs(pick, "held_out_objects", 1, 0, family_of("door-open"))
