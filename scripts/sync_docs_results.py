"""Regenerate every committed study report (``docs/results/<study>/``: report.md, report.html and plots from its
results.csv, config.yaml and family CSV files) and rewrite the tables of ``docs/*.md`` fenced from them
(``<!-- results: STUDY "SECTION" -->`` ... ``<!-- /results -->``, see ``lerobot_factorworld/study/published.py``).

    .venv/bin/python scripts/sync_docs_results.py           # after committing a study's new results.csv
    .venv/bin/python scripts/sync_docs_results.py --check   # change nothing; exit 1 naming what is stale

A fenced block that names a study with no committed results, or a section or table its report lacks, is an
error and nothing in docs/*.md is written.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from lerobot_factorworld.study.published import RESULTS_ROOT, committed_studies, stale_published, sync_published

ROOT = Path(__file__).resolve().parents[1]


def check(root: Path) -> list[str]:
    """What is stale: committed reports that differ from their regeneration, and fenced blocks that differ."""
    return stale_published(root)


def sync(root: Path) -> list[Path]:
    """Regenerate the committed reports in place, then rewrite the fenced blocks; the docs files changed."""
    return sync_published(root)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 if anything is stale")
    parser.add_argument("--root", type=Path, default=ROOT, help="repository root (default: this checkout)")
    args = parser.parse_args()
    try:
        if args.check:
            problems = check(args.root)
            for problem in problems:
                print(problem)
            sys.exit(1 if problems else 0)
        changed = sync(args.root)
    except (ValueError, OSError) as err:
        print(f"error: {err}", file=sys.stderr)
        sys.exit(1)
    studies = ", ".join(committed_studies(args.root / RESULTS_ROOT)) or "none"
    print(f"regenerated the committed reports ({studies}); rewrote {len(changed)} docs file(s)")
    for path in changed:
        print(f"  {path}")


if __name__ == "__main__":
    main()
