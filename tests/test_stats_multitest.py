"""Multiple testing as a pure function of p-values (stats/multitest.py): Holm's step-down and Bonferroni on
hand-worked examples, the levels and the step-down that claims.py decides with, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest

from lerobot_factorworld.stats.multitest import BONFERRONI, HOLM, multipletests, rank_levels, step_down

# Four hypotheses at alpha = 0.05. Sorted: 0.005 (#3), 0.01 (#0), 0.03 (#2), 0.04 (#1).
P = [0.01, 0.04, 0.03, 0.005]


def test_holm_steps_down_and_stops_at_the_first_kept_hypothesis():
    """Holm: 0.005 <= 0.05/4 = 0.0125 rejected; 0.01 <= 0.05/3 = 0.0167 rejected; 0.03 > 0.05/2 = 0.025 kept, so
    0.04, below its own level 0.05/1, is kept too. Adjusted: running max of (4 x 0.005, 3 x 0.01, 2 x 0.03, 1 x 0.04)
    = (0.02, 0.03, 0.06, 0.06), back in the given order."""
    out = multipletests(P, alpha=0.05, method=HOLM)
    assert out.reject.tolist() == [True, False, False, True]
    assert out.pvals_corrected == pytest.approx([0.03, 0.06, 0.06, 0.02], abs=1e-15)
    assert out.levels == pytest.approx([0.05 / 3, 0.05 / 1, 0.05 / 2, 0.05 / 4], abs=1e-15)
    assert (out.pvals_corrected <= 0.05).tolist() == out.reject.tolist()  # adjusted p-values reject alike


def test_bonferroni_tests_every_hypothesis_at_alpha_over_m():
    """Bonferroni: every p at 0.05/4 = 0.0125 (0.01 and 0.005 rejected); adjusted 4 x p, capped at 1."""
    out = multipletests(P, alpha=0.05, method=BONFERRONI)
    assert out.reject.tolist() == [True, False, False, True]
    assert out.pvals_corrected == pytest.approx([0.04, 0.16, 0.12, 0.02], abs=1e-15)
    assert out.levels == pytest.approx([0.0125] * 4, abs=1e-15)
    assert multipletests([0.3, 0.5], method=BONFERRONI).pvals_corrected.tolist() == [0.6, 1.0]


def test_holm_rejects_more_than_bonferroni_where_the_levels_differ():
    """0.01 and 0.02 at 0.05: Bonferroni's 0.025 rejects both too; 0.01 and 0.04: Holm's second level is 0.05, so
    it rejects both where Bonferroni (0.025) rejects only the first."""
    assert multipletests([0.01, 0.04], method=HOLM).reject.tolist() == [True, True]
    assert multipletests([0.01, 0.04], method=BONFERRONI).reject.tolist() == [True, False]
    assert multipletests([0.02, 0.01], method=BONFERRONI).reject.tolist() == [True, True]


def test_a_p_value_equal_to_its_level_is_rejected_and_ties_keep_their_order():
    """As statsmodels: reject where p <= level. Two equal p-values: the first given is tested first."""
    assert multipletests([0.025, 0.05], alpha=0.05).reject.tolist() == [True, True]
    out = multipletests([0.02, 0.02, 0.5], alpha=0.05)
    assert out.levels.tolist() == pytest.approx([0.05 / 3, 0.05 / 2, 0.05])
    assert out.reject.tolist() == [False, False, False]  # 0.02 > 0.0167: the step-down stops at once


def test_the_levels_and_the_step_down_claims_decide_with():
    """claims.py's comparison of rank k is decided at 1 - 0.05 / (m - k), and none after one left unresolved is
    resolved: the two halves, apart."""
    assert rank_levels(3, 0.05, HOLM) == (0.05 / 3, 0.05 / 2, 0.05 / 1)
    assert rank_levels(3, 0.05, BONFERRONI) == (0.05 / 3,) * 3
    assert rank_levels(0, 0.05, HOLM) == ()
    assert step_down([True, True, False, True]) == [True, True, False, False]
    assert step_down([False, True]) == [False, False]
    assert step_down([]) == []


def test_no_p_values_and_the_refusals():
    out = multipletests([], method=HOLM)
    assert out.reject.size == out.pvals_corrected.size == out.levels.size == 0
    with pytest.raises(ValueError, match="method must be one of holm, bonferroni"):
        multipletests(P, method="fdr_bh")
    with pytest.raises(ValueError, match=r"alpha must be in \(0, 1\)"):
        rank_levels(2, 1.0, HOLM)
    for bad in ([0.1, 1.2], [np.nan], [[0.1, 0.2]]):
        with pytest.raises(ValueError, match="p-values must be a vector"):
            multipletests(bad)
