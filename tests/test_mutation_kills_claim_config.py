"""A claim's validation (study/plan/claim_config.py) where mutation testing found the suite silent
(docs/testing.md): every refusal's exact text, what each kind needs at its boundary (one factor, exactly two,
two non-empty tiers, a baseline and factors), the method and baseline both checked, and the trend's and pair's
settings checked for their own kind only."""

from __future__ import annotations

import re

import pytest

from lerobot_factorworld.study.plan.claim_config import ClaimConfig

METHODS, TASKS = ["bc", "aug"], ["t1", "t2"]
FACTORS, PAIRS = ["light", "camera_pos", "table_texture"], ["light+camera_pos"]


def claim(kind: str, **settings) -> ClaimConfig:
    return ClaimConfig(**{"kind": kind, "text": "x", "source": "s", **settings})


def refused(config: ClaimConfig, message: str) -> None:
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        config.validate(METHODS, TASKS, FACTORS, PAIRS)


def test_a_kind_text_and_source_method_task_and_factors_name_what_the_study_has():
    refused(
        claim("gap"), "unknown claim kind 'gap'; valid: gap_opens, gap_exceeds, ordering, trend, pair, method_shrinks"
    )
    message = "a gap_opens claim needs its text and its source in the paper (text:, source:)"
    refused(claim("gap_opens", factors=["light"], text=""), message)
    refused(claim("gap_opens", factors=["light"], source=""), message)
    refused(claim("gap_opens", factors=["light"], method="rt1"), "unknown claim method 'rt1'; valid: bc, aug")
    refused(claim("gap_opens", factors=["light"], baseline="rt1"), "unknown claim method 'rt1'; valid: bc, aug")
    refused(claim("gap_opens", factors=["light"], task="t9"), "unknown claim task 't9'; valid: t1, t2")
    valid = "valid: light, camera_pos, table_texture"
    refused(claim("gap_opens", factors=["light", "fog"]), f"unknown factor of the claim 'x' 'fog'; {valid}")
    refused(claim("ordering", tiers=[["light"], ["fog"]]), f"unknown factor of the claim 'x' 'fog'; {valid}")
    claim("gap_opens", factors=["camera_pos"], method="aug", baseline="bc", task="t2").validate(
        METHODS, TASKS, FACTORS, PAIRS
    )


@pytest.mark.parametrize(
    "kind, settings, needs",
    [
        ("gap_opens", {}, "factors: [factor, ...]"),
        ("gap_exceeds", {"factors": ["light"]}, "factors: [harder, easier]"),
        ("gap_exceeds", {"factors": FACTORS}, "factors: [harder, easier]"),
        ("ordering", {"tiers": [["light"], []]}, "tiers: [[hardest, ...], [next, ...], ...] (two or more)"),
        ("ordering", {"tiers": [["light", "camera_pos"]]}, "tiers: [[hardest, ...], [next, ...], ...] (two or more)"),
        ("trend", {}, "factors: [factor, ...]"),
        ("pair", {}, "pair: a+b"),
        ("method_shrinks", {"factors": ["light"]}, "factors: [factor, ...] and baseline: <method>"),
        ("method_shrinks", {"baseline": "bc"}, "factors: [factor, ...] and baseline: <method>"),
    ],
)
def test_each_kind_refuses_what_it_lacks(kind, settings, needs):
    refused(claim(kind, **settings), f"claim 'x': a {kind} claim needs {needs}")


@pytest.mark.parametrize(
    "kind, settings",
    [
        ("gap_opens", {"factors": ["light"]}),
        ("gap_exceeds", {"factors": ["light", "camera_pos"]}),
        ("ordering", {"tiers": [["light"], [], ["camera_pos"]]}),
        ("trend", {"factors": ["light"], "over": "radius", "direction": "grows"}),
        ("pair", {"pair": "light+camera_pos", "relation": "synergistic"}),
        ("method_shrinks", {"factors": ["light"], "baseline": "bc"}),
        # a trend's and a pair's settings are checked on those kinds only
        ("gap_opens", {"factors": ["light"], "over": "time", "direction": "up", "relation": "x", "pair": "a+b"}),
    ],
)
def test_each_kind_takes_just_enough(kind, settings):
    claim(kind, **settings).validate(METHODS, TASKS, FACTORS, PAIRS)


def test_the_trend_and_pair_settings():
    trend = {"factors": ["light"]}
    refused(claim("trend", **trend, over="time"), "unknown claim over 'time'; valid: n, radius")
    refused(claim("trend", **trend, direction="up"), "unknown claim direction 'up'; valid: shrinks, grows")
    pair = {"pair": "light+camera_pos"}
    refused(claim("pair", **pair, relation="added"), "unknown claim relation 'added'; valid: within, synergistic")
    refused(claim("pair", pair="light+fog"), "unknown claim pair 'light+fog'; valid: light+camera_pos")
