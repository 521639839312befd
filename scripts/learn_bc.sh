#!/usr/bin/env bash
# The documented bc learning runs (docs/bc.md): scripted demos of one Factor World task in its N training
# environments -> lerobot-train (bc, conv encoder, CPU) -> lerobot-eval on those environments, then a summary
# (success with a Wilson 95% interval, per training environment) and the wall time of each stage.
# Every setting is an environment variable; the defaults are the documented door-open run.
#   TASK=pick-place DEMOS=150 bash scripts/learn_bc.sh
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-.venv/bin}
TASK=${TASK:-door-open}
N=${N:-5}
DEMOS=${DEMOS:-100}
STEPS=${STEPS:-5000}
BATCH=${BATCH:-32}
AUG=${AUG:-shift}
WORKERS=${WORKERS:-1}    # one dataloader process decodes frames while training runs on the other core
THREADS=${THREADS:-1}    # torch threads of the training process (2 threads were slower on the shared 2-core machine)
EPISODES=${EPISODES:-50}
SEED=${SEED:-1000}
OUT=${OUT:-outputs/bc_learning/$TASK}
export MUJOCO_GL=${MUJOCO_GL:-egl}

start=$(date +%s)
"$BIN/factorworld" collect --task="$TASK" --n_envs="$N" --demos="$DEMOS" --use_videos=false \
  --root="$OUT/data" --repo_id="local/bc_$TASK" --mode=overwrite
collected=$(date +%s)
OMP_NUM_THREADS="$THREADS" "$BIN/lerobot-train" --policy.type=bc --policy.augmentation="$AUG" --policy.device=cpu --policy.push_to_hub=false \
  --dataset.repo_id="local/bc_$TASK" --dataset.root="$OUT/data" --steps="$STEPS" --batch_size="$BATCH" \
  --num_workers="$WORKERS" --save_freq="$STEPS" --log_freq=200 --seed=0 --output_dir="$OUT/train"
trained=$(date +%s)
"$BIN/lerobot-eval" --policy.path="$OUT/train/checkpoints/last/pretrained_model" --env.type=factorworld \
  --env.task="$TASK" --env.n_train_envs="$N" --eval.n_episodes="$EPISODES" --eval.batch_size=1 --seed="$SEED" \
  --output_dir="$OUT/eval"
done_at=$(date +%s)
"$BIN/python" - "$OUT/eval/eval_info.json" "$N" "$SEED" <<'PY'
import json, math, sys
info, n_envs, seed = json.load(open(sys.argv[1])), int(sys.argv[2]), int(sys.argv[3])
successes = [bool(s) for task in info["per_task"] for s in task["metrics"]["successes"]]
k, n, z = sum(successes), len(successes), 1.96
centre = (k + z * z / 2) / (n + z * z)
half = z * math.sqrt(k * (n - k) / n + z * z / 4) / (n + z * z)
print(f"success on the {n_envs} training environments: {k}/{n} = {100 * k / n:.1f}% "
      f"(Wilson 95% interval {100 * (centre - half):.1f}-{100 * (centre + half):.1f}%)")
from lerobot_factorworld.envs.factor_env import env_index_for_seed  # episode i is reset with seed SEED + i
per_env = [[s for i, s in enumerate(successes) if env_index_for_seed(seed + i, n_envs) == e] for e in range(n_envs)]
print("per training environment: " + ", ".join(f"env {e}: {sum(s)}/{len(s)}" for e, s in enumerate(per_env)))
PY
echo "wall time: collect $((collected - start)) s, train $((trained - collected)) s, eval $((done_at - trained)) s, total $((done_at - start)) s"
