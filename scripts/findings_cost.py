"""What the whole set of findings costs when their shared steps run once (as ``make findings`` runs them).

Every finding's config prints its own ``--dry-run`` cost as if it ran alone, but the findings share steps (a step
with the same key is the same result: F3's seed-0 datasets and trainings are F1's, F5's, F8's, ...), and
``scripts/run_findings.sh`` runs them in an order that reuses each finished study's steps. This script plans every
config listed there, in that order, and estimates with the study's cost model (``study/plan/cost.py``, 2 cores) each
one's steps that no config before it has: the set's cost with shared steps counted once. It also totals the set
of each finding's first config (F1 to F9, one each: what issue 19 sized at about 12 hours), the others being
follow-ups that test an explanation. Plans only: nothing runs; it reads the configs and the cost model.

    .venv/bin/python scripts/findings_cost.py            # a Markdown table, then the two totals

The model's constants come from the quick study (``study/cost_model.json``); the findings' 60-epoch trainings ran
1.3-1.4 times the model on the 2-core machine, and 168 px frames cost more than its per-frame rate (the configs'
headers say so), so read these as lower bounds of the wall time.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

from lerobot_factorworld.core.settings import parse_config
from lerobot_factorworld.study.plan import cost
from lerobot_factorworld.study.plan.command import StudyCommand
from lerobot_factorworld.study.plan.grid import Plan, make_plan

REPO_ROOT = Path(__file__).resolve().parents[1]
RUN_FINDINGS = REPO_ROOT / "scripts" / "run_findings.sh"
CONFIGS = REPO_ROOT / "configs" / "study" / "findings"
PROFILE = "one CPU machine (2 cores)"


def findings_order(script: Path = RUN_FINDINGS) -> list[str]:
    """The config names of ``run_findings.sh``'s ``FINDINGS=( ... )`` list, in its order (the one source of it)."""
    match = re.search(r"^FINDINGS=\(\n(.*?)^\)", script.read_text(), flags=re.MULTILINE | re.DOTALL)
    if match is None:
        raise SystemExit(f"error: no FINDINGS=( ... ) list in {script}")
    return match.group(1).split()


def first_of_each_finding(names: list[str]) -> list[str]:
    """The first config of each finding (``f1_...`` to ``f9_...``) in ``names``' order."""
    firsts: dict[str, str] = {}
    for name in names:
        firsts.setdefault(name.split("_")[0], name)
    return list(firsts.values())


def plan_configs(names: list[str]) -> dict[str, Plan]:
    """Each config's plan, made once (the totals below reuse them)."""
    return {
        name: make_plan(parse_config(StudyCommand, [f"--config_path={CONFIGS / name}.yaml"], "study").grid())
        for name in names
    }


def costs(names: list[str], plans: dict[str, Plan] | None = None) -> list[tuple[str, float, int, int, float]]:
    """Per config, in order: (name, hours alone, its steps no config before it has, its steps, their hours)."""
    plans = plans or plan_configs(names)
    seen: set[str] = set()
    rows = []
    for name in names:
        plan = plans[name]
        new = [step for step in plan.steps if step.key not in seen]
        alone = cost.estimate(plan, list(plan.steps))[PROFILE]
        rows.append((name, alone, len(new), len(plan.steps), cost.estimate(plan, new)[PROFILE] if new else 0.0))
        seen |= {step.key for step in plan.steps}
    return rows


def main() -> None:
    names = findings_order()
    plans = plan_configs(names)
    rows = costs(names, plans)
    print("| config | alone (h) | steps not run before it | with reuse (h) |\n|---|---|---|---|")
    for name, alone, new, total, hours in rows:
        print(f"| {name} | {alone:.2f} | {new} of {total} | {hours:.2f} |")
    every = sum(row[4] for row in rows)
    print(f"\nall {len(rows)} configs: {sum(row[1] for row in rows):.1f} h alone, {every:.1f} h with shared steps once")
    core = costs(first_of_each_finding(names), plans)
    print(f"the first config of each finding ({len(core)}): {sum(row[1] for row in core):.1f} h alone, "
          f"{sum(row[4] for row in core):.1f} h with shared steps once")  # fmt: skip


if __name__ == "__main__":
    sys.exit(main())
