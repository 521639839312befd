"""Per-module mutation scores from ``mutmut results --all true`` (stdin), for ``make mutation``.

Killed counts mutants a test failed on (a timeout counts: the tests noticed); the equivalent mutants listed in
docs/testing.md (lines ``- `<mutant name>`: <reason>``) are left out of the total. Prints the table of
docs/testing.md and the survivors that are not listed as equivalent; exits 1 when a module is below 90%.
"""

from __future__ import annotations

import re
import sys
from collections import Counter, defaultdict
from pathlib import Path

DOC = Path(__file__).resolve().parents[1] / "docs" / "testing.md"
TARGET = 0.9
KILLED = ("killed", "timeout", "segfault", "caught by type check")
EQUIVALENT = re.compile(r"^- `([\w.]+__mutmut_\d+)`")


def main() -> int:
    listed = DOC.read_text().splitlines() if DOC.exists() else []
    equivalent = {m.group(1) for line in listed if (m := EQUIVALENT.match(line))}
    counts: dict[str, Counter] = defaultdict(Counter)
    survivors = []
    for line in sys.stdin:
        name, sep, status = line.strip().rpartition(": ")
        if not sep or "__mutmut_" not in name:
            continue
        module = name.split(".x_")[0].split(".xǁ")[0]
        if name in equivalent:
            counts[module]["equivalent"] += 1
        elif status in KILLED:
            counts[module]["killed"] += 1
        else:
            counts[module]["missed"] += 1
            survivors.append(f"{name}: {status}")
    print("| module | killed | total | equivalent | score |")
    print("|---|---:|---:|---:|---:|")
    low = False
    for module in sorted(counts):
        c = counts[module]
        total = c["killed"] + c["missed"]
        score = c["killed"] / total if total else 1.0
        low |= score < TARGET
        print(f"| `{module}` | {c['killed']} | {total} | {c['equivalent']} | {score:.1%} |")
    for line in survivors:
        print("survived:", line)
    return 1 if low else 0


if __name__ == "__main__":
    sys.exit(main())
