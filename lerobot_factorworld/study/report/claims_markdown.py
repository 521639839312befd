"""The report's claims section and its ordering sentence, both from ``claims.decide``: a verdict printed
anywhere in a report is the one its intervals give."""

from __future__ import annotations

import math
from collections.abc import Sequence

from ...stats.bootstrap import BOOTSTRAP_RESAMPLES
from ..results.claims import AGREES, CAPPED, CONFOUNDED, DISAGREES, ClaimVerdict, Decided

CLAIMS_HEADING = "## The paper's claims"


def _num(value: float) -> str:
    return "n/a" if not math.isfinite(value) else f"{value:+.3f}"


def _interval(d: Decided) -> str:
    if math.isfinite(d.low) and math.isfinite(d.high):
        return f"[{d.low:+.3f}, {d.high:+.3f}] at {d.level:.2%}"
    low, high = d.bootstrap
    if d.seeds < 2 and math.isfinite(low) and math.isfinite(high):
        return f"none (one seed; episodes only: [{low:+.3f}, {high:+.3f}] at {d.level:.2%})"
    return "none"


def to_resolve(d: Decided) -> str:
    """What the comparison's verdict rests on, in words: for an unresolved one, what this design resolves and
    what would resolve the observed effect (which way, where it leans the other way)."""
    if d.verdict == CONFOUNDED:
        why = "the treatment's P_T is at most the baseline's gap" if d.forced else "P_T is resolved lower"
        return f"the gap shrank, but {why} and P_F is not resolved higher: success fell, generalization did not improve"
    if d.verdict in (AGREES, DISAGREES):
        return "resolved"
    if d.verdict == CAPPED:
        lean = "; the estimate leans the other way" if d.leans_other_way else ""
        if not math.isfinite(d.smallest):
            return "these success rates leave no effect this design resolves" + lean
        other = (
            f", and at most {d.contrary:.3f} the other way" if d.leans_other_way and math.isfinite(d.contrary) else ""
        )
        return f"at most {d.headroom:.3f} the paper's way{other}, below the {d.smallest:.3f} this design resolves"
    # not resolved: ``smallest`` is NaN only when the episode counts are unknown (claims._verdict)
    parts = [f"resolves {d.smallest:.3f} (episode noise)" if math.isfinite(d.smallest) else "episode counts unknown"]
    if d.forced:
        parts.append(
            "its sign is forced (the treatment's P_T is at most the baseline's gap): it can agree only with P_F "
            "resolved higher"
        )
    effect = abs(d.point - d.threshold)
    if not math.isfinite(effect) or effect == 0:
        parts.append("no effect observed")
        return "; ".join(parts)
    if d.leans_other_way and math.isfinite(d.headroom) and d.headroom < d.smallest:
        parts.append(f"capped the paper's way (at most {d.headroom:.3f}); leans the other way, toward disagrees")
    side = " toward disagrees" if d.leans_other_way else ""
    parts.append(
        f"episode noise: {effect:.3f}{side} at ≥{d.episodes_needed:.0f} episodes per cell"
        if math.isfinite(d.episodes_needed)
        else f"episode noise: {effect:.3f}{side} at more episodes than any study runs"
    )
    if d.seeds < 2:
        low, high = d.bootstrap
        episodes_resolve = math.isfinite(low) and (low > d.threshold or high < d.threshold)
        parts.append(
            "a second training seed (one seed has no seed-level interval"
            + ("; its episodes alone resolve it)" if episodes_resolve else ")")
        )
    elif math.isfinite(d.seeds_needed):
        parts.append(f"seed spread: ≈{d.seeds_needed:.0f} seeds")
    return "; ".join(parts)


def _success_changes(d: Decided) -> str:
    """`` (P_T -0.550 [..], P_F -0.225 [..])``: a shrink's success changes beside its gap change ("" otherwise)."""
    if d.p_t_change is None or d.p_f_change is None:
        return ""
    changes = ", ".join(
        f"{name} {point:+.3f} [{low:+.3f}, {high:+.3f}]" for name, (point, low, high) in (("P_T", d.p_t_change), ("P_F", d.p_f_change))
    )  # fmt: skip
    return f" ({changes}{'; episodes only' if d.seeds < 2 else ''}; {d.cells} cells)"


def claim_cells(v: ClaimVerdict) -> tuple[str, str, str]:
    """(estimate, interval, what would resolve it) of a claim: its comparison, or an ordering's count and the
    comparison that decides it (the one that disagrees, else the weakest)."""
    d = v.summary
    if d is None:
        if v.claim.baseline:  # two methods: compared only where both ran
            return "n/a", "none", f"{v.claim.method} and {v.claim.baseline} share no cell (task, N, seed, condition)"
        return "no data", "none", "the study has no rows for it"
    if len(v.comparisons) == 1:
        return _num(d.point) + _success_changes(d), _interval(d), to_resolve(d)
    if v.claim.kind == "pair" and v.claim.relation == "within" and len(v.comparisons) == 2:  # a ±band
        low, high = sorted(c.threshold for c in v.comparisons)
        return f"{_num(d.point)} (the paper: between {low:+g} and {high:+g})", _interval(d), to_resolve(d)
    counts = {verdict: sum(c.verdict == verdict for c in v.comparisons) for verdict in (AGREES, DISAGREES)}
    estimate = (
        f"{counts[AGREES]} of {len(v.comparisons)} comparisons agree, {counts[DISAGREES]} disagree; "
        f"{'against' if d.verdict == DISAGREES else 'weakest'}: {d.label} {_num(d.point)}"
    )
    return estimate, _interval(d), to_resolve(d)


def claims_section(verdicts: Sequence[ClaimVerdict], finding: str = "", others: Sequence[str] = ()) -> list[str]:
    """The claims table (claim, source, estimate, interval, verdict), what its correction covered, and every
    comparison behind it; ``finding`` and ``others``: the finding and its other studies corrected with these."""
    if not verdicts:
        return []
    comparisons = comparison_rows(verdicts)
    m = verdicts[0].corrected_over
    scope = (
        f"the {m} comparisons of finding {finding} over its studies here and beside this one ({', '.join(others)}), "
        "a comparison one of them re-reports from another's cells counted once and decided on the larger's cells"
        if others
        else f"the {m} comparisons of this study"
    )
    lines = [
        CLAIMS_HEADING,
        "",
        "Each claim is tested by comparisons (a mean gap against 0, or one factor's or method's gap against another's, "
        "a change over N, a slope over the radius, a pair metric against the ±band), decided at 95% with Holm's "
        f"correction over {scope}: each on the hull of two seed-level intervals, the "
        f"bootstrap's ({BOOTSTRAP_RESAMPLES} resamples) and a t-interval over training seeds (none with one seed, so "
        "nothing is resolved there). Two methods, or two N, are compared on the cells (task, N, seed, condition) both "
        "have. **agrees** / **disagrees**: the interval lies on the paper's / the other side; "
        f"**{CONFOUNDED}**: a gap resolved smaller while the treatment's P_T is resolved lower (or is at most the "
        "baseline's gap, which forces the sign) and its P_F is not resolved higher, so success fell rather than "
        "generalization improved (a shrink's estimate shows the P_T and P_F changes, treatment minus baseline, at the "
        "same level); **capped**: the success rates leave less room the paper's way than the design resolves, and "
        "the estimate does not lean the other way with room there; **not resolved**: otherwise. A claim of several "
        "comparisons disagrees if one does and agrees only if all do. What would resolve it: the episodes per cell "
        "at these seeds (episode noise only, a lower bound) and the seeds at the observed spread between seeds "
        "(`study/results/claims.py`).",
        "",
        "| " + " | ".join(CLAIM_COLUMNS) + " |",
        "|---|---|---|---|---|---|",
    ]
    for claim, source, estimate, interval, verdict, resolve in claim_rows(verdicts):
        lines.append(f"| {claim} | {source} | {estimate} | {interval} | **{verdict}** | {resolve} |")
    studies = ", ".join(dict.fromkeys([*(s for v in verdicts for s in v.studies[:1]), *others]))
    lines += [
        "",
        "| correction | comparisons | studies |",
        "|---|---|---|",
        f"| Holm over {'finding ' + finding if others else 'this study'} | {m} | {studies} |",
    ]
    borrowed = [v for v in verdicts if len(v.studies) > 1]
    if borrowed:
        lines.append("")
        lines += [
            f"- *{v.claim.text}* is decided once for {', '.join(v.studies)}, on the larger study's cells, "
            f"{v.comparisons[0].cells if v.comparisons else 0} cells in all."
            for v in borrowed
        ]
    if comparisons:
        lines += ["", "| " + " | ".join(COMPARISON_COLUMNS) + " |", "|---|---|---|---|---|---|"]
        lines += ["| " + " | ".join(row) + " |" for row in comparisons]
    lines.append("")
    return lines


CLAIM_COLUMNS = ("claim", "source", "estimate", "interval", "verdict", "to resolve")
COMPARISON_COLUMNS = ("comparison", "estimate", "interval", "p", "verdict", "to resolve")


def claim_rows(verdicts: Sequence[ClaimVerdict]) -> list[tuple[str, str, str, str, str, str]]:
    """The claims table's cells (:data:`CLAIM_COLUMNS`), one row per claim, as report.md and report.html print
    them."""
    out = []
    for v in verdicts:
        estimate, interval, resolve = claim_cells(v)
        claim = v.claim.text + (f" ({v.claim.task})" if v.claim.task else "")
        out.append((claim, v.claim.source, estimate, interval, v.verdict, resolve))
    return out


def comparison_rows(verdicts: Sequence[ClaimVerdict]) -> list[tuple[str, str, str, str, str, str]]:
    """Every comparison behind the claims, once (:data:`COMPARISON_COLUMNS`), named with its claim's task and, where
    the claims name different methods, its method (unnamed: the study's first); none when each claim is one
    comparison (the claims table shows them all)."""
    if not any(len(v.comparisons) > 1 for v in verdicts):
        return []
    several_methods = len({v.claim.method for v in verdicts}) > 1  # name a claim's method where claims differ
    seen: dict[str, Decided] = {}
    for v in verdicts:
        named = [v.claim.method if several_methods else None, v.claim.task]
        qualifier = ", ".join(q for q in named if q)
        for d in v.comparisons:
            seen.setdefault(d.label + (f" ({qualifier})" if qualifier else ""), d)
    return [
        (label, _num(d.point), _interval(d), f"{d.p_value:.4f}", d.verdict, to_resolve(d)) for label, d in seen.items()
    ]


def ordering_sentence(verdicts: Sequence[ClaimVerdict]) -> str:
    """One line on the paper's ordering, from its claims' verdicts ("" when the study tests none)."""
    found = [v for v in verdicts if v.claim.kind == "ordering"]
    if not found:
        return ""
    parts = []
    for v in found:
        agree = sum(c.verdict == AGREES for c in v.comparisons)
        against = sum(c.verdict == DISAGREES for c in v.comparisons)
        parts.append(
            f"{v.claim.text}: **{v.verdict}** ({agree} of {len(v.comparisons)} comparisons resolved the paper's way, "
            f"{against} the other way)"
        )
    return "Against the paper's ordering (decided in *The paper's claims* below): " + "; ".join(parts) + "."
