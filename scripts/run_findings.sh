#!/usr/bin/env bash
# Every finding of docs/findings.md, one study after another, each reusing the finished steps of the studies
# before it (`reuse_from`: a step with the same key is the same result, docs/study.md). The order makes the most
# of that: F3's seed-0 datasets, trainings and single-factor evaluations are also F1's, F5's, F6's and F8's, and
# F1's N = 5 steps are F2's, F4's and F8's. Resumable: run it again and it goes on where it stopped (finished
# steps are never redone). With each shared step run once, 41.0 hours on 2 cores by the cost model
# (scripts/findings_cost.py; F1 at five seeds and two arms is 8.3 of them, F8's RT-1 arms about 15); the bc
# findings ran here about 1.3x slower than the model says, and a lone RT-1 training about 2x faster (docs/rt1.md,
# "128 epochs"). One study at a time uses both cores.
#   bash scripts/run_findings.sh                              # run all, into outputs/study/findings/<config>/
#   DRY_RUN=1 bash scripts/run_findings.sh                    # each study's --dry-run (steps, cost, power)
#   ONLY="f3_pairs f1_ordering" bash scripts/run_findings.sh  # some of them, in this script's order
# Publish one as docs/findings.md says ("factorworld report ... --out=docs/results/<config>").
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-.venv/bin}
OUT=${OUT:-outputs/study/findings}
export MUJOCO_GL=${MUJOCO_GL:-egl}

FINDINGS=(
  f3_pairs
  f1_ordering
  f5_augmentation
  f8_out_of_domain
  f8_out_of_domain_language
  f8_out_of_domain_language_epochs
  f2_gap_vs_n
  f2_gap_vs_n_400_demos
  f4_radius
  f6_pretrained
  f7_object_texture_images
  f7_object_texture_colours
  f7_object_texture_168px
  f9_pick
)

for name in ${ONLY:-}; do
  [[ " ${FINDINGS[*]} " == *" $name "* ]] || { echo "error: unknown finding '$name'; valid: ${FINDINGS[*]}" >&2; exit 2; }
done

done_folders=()
failed=()
for name in "${FINDINGS[@]}"; do
  if [[ -z "${ONLY:-}" || " $ONLY " == *" $name "* ]]; then
    reuse=$(IFS=,; echo "${done_folders[*]}")
    echo "== $name${reuse:+ (reusing $reuse)}"
    # A study that fails (a step's error, a missing weights file) does not stop the others: listed at the end.
    "$BIN/factorworld" study --config "configs/study/findings/$name.yaml" --out_dir="$OUT/$name" \
      ${reuse:+--reuse_from=[$reuse]} ${DRY_RUN:+--dry-run} || failed+=("$name")
  fi
  if [[ -d "$OUT/$name/steps" ]]; then
    done_folders+=("$OUT/$name")
  fi
done
if (( ${#failed[@]} )); then
  echo "error: these findings did not finish: ${failed[*]} (their errors are above; run again to retry them)" >&2
  exit 1
fi
