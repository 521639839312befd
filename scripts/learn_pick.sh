#!/usr/bin/env bash
# The documented pick run (docs/pick.md): scripted pick demos in N training environments (the real-robot
# factors varied) -> RT-1 (small preset, CPU) trained across all instructions -> lerobot-eval on the
# paper's real-robot conditions plus held-out phrasings and objects -> the table (scripts/pick_report.py).
# Every stage is skipped when its output exists, and training resumes from its last checkpoint, so
# re-running the same command after an interruption continues where it stopped.
# Every setting is an environment variable with the documented value as default.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-.venv/bin}
N=${N:-10}
OBJECTS=${OBJECTS:-3}
DEMOS=${DEMOS:-200}
STEPS=${STEPS:-8000}
BATCH=${BATCH:-16}
TEST_ENVS=${TEST_ENVS:-10}
EPISODES=${EPISODES:-30}
OUT=${OUT:-outputs/pick}
FACTORS=${FACTORS:-floor_texture,distractors,light,table_texture,camera_pos}
CONDITIONS=${CONDITIONS:-floor_texture distractors light table_texture camera_pos table_texture+floor_texture table_texture+distractors held_out_phrasings held_out_objects}
export MUJOCO_GL=${MUJOCO_GL:-egl}
mkdir -p "$OUT"

stamp() { date +%s; }
t0=$(stamp)
if [ ! -f "$OUT/data/meta/factorworld.json" ]; then
  "$BIN/factorworld" collect --task=pick --factors="[$FACTORS]" --n_envs="$N" --demos="$DEMOS" \
    --sampling.n_objects="$OBJECTS" --use_videos=false --workers=1 --root="$OUT/data" --repo_id=local/pick
fi
t1=$(stamp)
CKPT="$OUT/train/checkpoints/last/pretrained_model"
if [ ! -f "$OUT/train/done" ]; then
  if [ -f "$OUT/train/checkpoints/last/training_state/training_step.json" ]; then
    "$BIN/lerobot-train" --config_path="$CKPT/train_config.json" --resume=true
  else
    rm -rf "$OUT/train"
    "$BIN/lerobot-train" --policy.type=rt1 --policy.preset=small --policy.device=cpu --policy.push_to_hub=false \
      --dataset.repo_id=local/pick --dataset.root="$OUT/data" --steps="$STEPS" --batch_size="$BATCH" \
      --num_workers=1 --save_freq=1000 --log_freq=200 --seed=0 --output_dir="$OUT/train"
  fi
  touch "$OUT/train/done"
fi
t2=$(stamp)
for condition in train $CONDITIONS; do
  dir="$OUT/eval/$condition"
  [ -f "$dir/eval_info.json" ] && continue
  rm -rf "$dir"
  if [ "$condition" = train ]; then
    shift_args=(--env.include_train=true)
  else
    shift_args=(--env.include_train=false "--env.shifts=[$condition]")
  fi
  "$BIN/lerobot-eval" --policy.path="$CKPT" --env.type=factorworld --env.task=pick --env.dataset_root="$OUT/data" \
    "${shift_args[@]}" --env.n_test_envs="$TEST_ENVS" --eval.n_episodes="$EPISODES" --eval.batch_size=1 \
    --seed=1000 --output_dir="$dir"
done
t3=$(stamp)
"$BIN/python" scripts/pick_report.py --out="$OUT" --test_envs="$TEST_ENVS" --start_seed=1000 | tee "$OUT/report.md"
echo "wall time: collect $((t1 - t0)) s, train $((t2 - t1)) s, eval $((t3 - t2)) s (this invocation)"
