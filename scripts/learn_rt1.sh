#!/usr/bin/env bash
# The documented RT-1 learning run (docs/rt1.md): scripted demos of one Factor World task in its N
# training environments -> lerobot-train (small preset, CPU) -> lerobot-eval on those environments.
# Every setting is an environment variable with the documented value as default.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-.venv/bin}
TASK=${TASK:-handle-press}
N=${N:-5}
DEMOS=${DEMOS:-100}
STEPS=${STEPS:-3000}
BATCH=${BATCH:-16}
EPISODES=${EPISODES:-50}
OUT=${OUT:-outputs/rt1_learning}
export MUJOCO_GL=${MUJOCO_GL:-egl}

start=$(date +%s)
"$BIN/factorworld" collect --task="$TASK" --n_envs="$N" --demos="$DEMOS" --use_videos=false \
  --root="$OUT/data" --repo_id=local/rt1_learning --mode=overwrite
collected=$(date +%s)
"$BIN/lerobot-train" --policy.type=rt1 --policy.preset=small --policy.device=cpu --policy.push_to_hub=false \
  --dataset.repo_id=local/rt1_learning --dataset.root="$OUT/data" --steps="$STEPS" --batch_size="$BATCH" \
  --num_workers=1 --save_freq="$STEPS" --log_freq=100 --seed=0 --output_dir="$OUT/train"
trained=$(date +%s)
"$BIN/lerobot-eval" --policy.path="$OUT/train/checkpoints/last/pretrained_model" --env.type=factorworld \
  --env.task="$TASK" --env.n_train_envs="$N" --eval.n_episodes="$EPISODES" --eval.batch_size=1 --seed=1000 \
  --output_dir="$OUT/eval"
done_at=$(date +%s)
"$BIN/python" - "$OUT/eval/eval_info.json" <<PY
import json, sys
info = json.load(open(sys.argv[1]))
print(f"success on the $N training environments of $TASK: {info['overall']['pc_success']:.1f}% "
      f"over {info['overall']['n_episodes']} episodes")
PY
echo "wall time: collect $((collected - start)) s, train $((trained - collected)) s, eval $((done_at - trained)) s"
