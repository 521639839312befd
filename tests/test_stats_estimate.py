"""The one estimate type (stats/estimate.py) and the decision interval that returns it (stats/decision.py)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from lerobot_factorworld.stats.decision import HULL, decision_interval
from lerobot_factorworld.stats.estimate import Estimate


def test_an_estimate_is_a_frozen_value_with_named_ends():
    e = Estimate(0.2, 0.1, 0.35, 0.95, "wilson")
    assert (e.point, e.low, e.high, e.level, e.method) == (0.2, 0.1, 0.35, 0.95, "wilson")
    assert e == Estimate(0.2, 0.1, 0.35, 0.95, "wilson") and hash(e) == hash(Estimate(0.2, 0.1, 0.35, 0.95, "wilson"))
    with pytest.raises(dataclasses.FrozenInstanceError):
        e.low = 0.0  # type: ignore[misc]


def test_excludes_and_defined():
    e = Estimate(0.2, 0.1, 0.35, 0.95, "wilson")
    assert e.defined and e.excludes(0.0) and e.excludes(0.4) and not e.excludes(0.1) and not e.excludes(0.2)
    none = Estimate(math.nan, math.nan, math.nan, 0.95, HULL)
    assert not none.defined and not none.excludes(0.0)


def test_a_reversed_interval_or_a_level_outside_0_1_is_refused():
    with pytest.raises(ValueError, match="low 0.3 above high 0.1"):
        Estimate(0.2, 0.3, 0.1, 0.95, "wilson")
    for level in (0.0, 1.0, 95):
        with pytest.raises(ValueError, match=r"level must be in \(0, 1\)"):
            Estimate(0.2, 0.1, 0.3, level, "wilson")


def test_the_decision_interval_is_an_estimate_around_the_given_point():
    """One seed: no seed-level interval (NaN ends), the point and level kept."""
    hull = decision_interval(0.4, np.array([0.3, 0.4, 0.5]), np.array([0.4]), 0.9)
    assert hull.point == 0.4 and hull.level == 0.9 and hull.method == HULL
    assert math.isnan(hull.low) and math.isnan(hull.high)
