"""Regenerate lerobot_factorworld/assets/asset_splits.json, the single source of the built-in splits.

It holds both split modes: ``family`` (whole families held out, the default) and ``variant`` (name by
name). Deterministic: running it twice writes identical bytes. Run it after adding families, changing
VARIANTS_PER_FAMILY, the curated Meta-World lists or their families, TRAIN_FRACTION, a task's
object_family or the tasks themselves (the textures their Meta-World scenes show are kept in train);
tests fail until the file matches. It refuses to write a split smaller than the paper's pools
(PAPER_SPLIT_SIZES).

    python scripts/make_asset_splits.py [--check]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from lerobot_factorworld.assets.library import (  # noqa: E402
    ASSET_SPLITS,
    KINDS,
    PAPER_SPLIT_SIZES,
    SPLITS,
    SPLITS_FILE,
)
from lerobot_factorworld.assets.split_document import builtin_splits_document  # noqa: E402


def render() -> str:
    """The exact text of the splits file."""
    return json.dumps(builtin_splits_document(), indent=1, sort_keys=True) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only verify the committed file is up to date")
    args = parser.parse_args()
    text = render()
    doc = json.loads(text)
    too_small = []
    for mode in ASSET_SPLITS:
        for kind in KINDS:
            counts = doc["counts"][mode][kind]
            families = doc["splits"][mode][kind]["families"]
            sides = "  ".join(f"{s}={counts[s]} ({len(families[s])} families)" for s in SPLITS)
            print(f"{mode:7s} {kind:8s} {sides}  total={sum(counts.values())}")
            too_small += [
                f"{mode} {kind} {s}: {counts[s]} < {PAPER_SPLIT_SIZES[kind][s]}"
                for s in SPLITS
                if counts[s] < PAPER_SPLIT_SIZES[kind][s]
            ]
    print(
        "kept in train (seen in the default scenes): "
        + "; ".join(f"{k}s {', '.join(v)}" for k, v in doc["seen_families"].items())
    )
    if too_small:
        print(
            f"splits smaller than the paper's pools: {'; '.join(too_small)}; add families or variants", file=sys.stderr
        )
        return 1
    current = SPLITS_FILE.read_text(encoding="utf-8") if SPLITS_FILE.exists() else None
    if args.check:
        if current != text:
            print(f"{SPLITS_FILE} is out of date; run: python scripts/make_asset_splits.py", file=sys.stderr)
            return 1
        print(f"{SPLITS_FILE} is up to date")
        return 0
    SPLITS_FILE.write_text(text, encoding="utf-8")
    print(f"wrote {SPLITS_FILE} (sha256 of lists {doc['sha256'][:16]}...)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
