"""The episodes a study's evaluations recorded (``recording.py``), gathered for its report: copied into
``episodes/`` next to ``report.md`` with ``episodes/episodes.json``, one entry per recorded episode (its cell,
condition, index, reset seed, success, furthest stage and video), which ``report.html``'s paired-episode viewer
reads: episode ``i`` of ``train`` and of a shifted condition of the same checkpoint start the object at the
same place.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Sequence
from pathlib import Path

from ...core.io import atomic_write_text
from ..results.rows import Evaluation
from ..run.recording import RECORDED_KEY, VIDEOS_DIR

MANIFEST = "episodes.json"
LABEL_KEYS = ("method", "task", "n_train_envs", "seed", "widths")


def collect_videos(evaluations: Sequence[Evaluation], study_dir: str | Path) -> Path | None:
    """Copy every finished evaluation's recorded videos into ``study_dir/episodes/`` and write the viewer's
    ``episodes.json`` (``None``, and any old copy removed, when no evaluation recorded one)."""
    out_dir = Path(study_dir) / VIDEOS_DIR
    entries = []
    for ev in evaluations:
        recorded = ev.result.get(RECORDED_KEY) or []
        labels = {k: ev.labels.get(k) for k in LABEL_KEYS}
        condition = ev.result["condition"]
        for rec in recorded:
            source = ev.step.folder(study_dir) / rec["video"]
            if not source.is_file():
                continue
            name = f"{ev.step.key}_{rec['index']:03d}.webm"
            out_dir.mkdir(parents=True, exist_ok=True)
            if not (out_dir / name).is_file():
                shutil.copyfile(source, out_dir / name)
            i = rec["index"]
            entries.append(
                {
                    **labels,
                    "condition": condition,
                    "index": i,
                    "episode_seed": rec["seed"],
                    "success": bool(ev.result["successes"][i]),
                    "stage": ev.result.get("stages", [None] * (i + 1))[i],
                    "length": ev.result.get("lengths", [None] * (i + 1))[i],
                    "video": f"{VIDEOS_DIR}/{name}",
                }
            )
    if not entries:
        shutil.rmtree(out_dir, ignore_errors=True)
        return None
    entries.sort(key=lambda e: (*(str(e[k]) for k in LABEL_KEYS), e["condition"], e["index"]))
    return atomic_write_text(out_dir / MANIFEST, json.dumps(entries, indent=1) + "\n")


def videos_bytes(study_dir: str | Path) -> int:
    """The disk the study's collected videos take (``episodes/``), in bytes."""
    folder = Path(study_dir) / VIDEOS_DIR
    return sum(p.stat().st_size for p in folder.glob("*.webm")) if folder.is_dir() else 0
