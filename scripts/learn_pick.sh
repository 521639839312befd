#!/usr/bin/env bash
# The documented pick run (docs/pick.md): scripted pick demos in N training environments (the real-robot
# factors varied) -> RT-1 (small preset, CPU) or, with POLICY=bc, the simulation CNN policy conditioned on the
# instruction embedding, trained across all instructions -> lerobot-eval on the paper's real-robot
# conditions plus held-out phrasings and objects -> the table (scripts/pick_report.py).
#   bash scripts/learn_pick.sh              # RT-1 small: data in outputs/pick/data, run in outputs/pick
#   POLICY=bc bash scripts/learn_pick.sh    # bc + language, same data, run in outputs/pick/bc
# Every stage is skipped when its output exists, and training resumes from its last checkpoint, so
# re-running the same command after an interruption continues where it stopped.
# Every setting is an environment variable with the documented value as default.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-.venv/bin}
N=${N:-10}
OBJECTS=${OBJECTS:-3}
DEMOS=${DEMOS:-200}
POLICY=${POLICY:-rt1}
case "$POLICY" in
  rt1) STEPS=${STEPS:-8000}; BATCH=${BATCH:-16}
       POLICY_ARGS=(--policy.type=rt1 --policy.preset=small) ;;
  bc)  STEPS=${STEPS:-5000}; BATCH=${BATCH:-32}
       POLICY_ARGS=(--policy.type=bc --policy.use_language=true --policy.augmentation=shift) ;;
  *)   echo "error: unknown POLICY '$POLICY'; valid: rt1, bc" >&2; exit 2 ;;
esac
TEST_ENVS=${TEST_ENVS:-10}
EPISODES=${EPISODES:-30}
OUT=${OUT:-outputs/pick}                       # the dataset lives in $OUT/data
if [ "$POLICY" = rt1 ]; then RUN=${RUN:-$OUT}; else RUN=${RUN:-$OUT/$POLICY}; fi  # train/ and eval/
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
CKPT="$RUN/train/checkpoints/last/pretrained_model"
if [ ! -f "$RUN/train/done" ]; then
  if [ -f "$RUN/train/checkpoints/last/training_state/training_step.json" ]; then
    "$BIN/lerobot-train" --config_path="$CKPT/train_config.json" --resume=true
  else
    rm -rf "$RUN/train"
    mkdir -p "$RUN"
    "$BIN/lerobot-train" "${POLICY_ARGS[@]}" --policy.device=cpu --policy.push_to_hub=false \
      --dataset.repo_id=local/pick --dataset.root="$OUT/data" --steps="$STEPS" --batch_size="$BATCH" \
      --num_workers=1 --save_freq=1000 --log_freq=200 --seed=0 --output_dir="$RUN/train"
  fi
  touch "$RUN/train/done"
fi
t2=$(stamp)
for condition in train $CONDITIONS; do
  dir="$RUN/eval/$condition"
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
"$BIN/python" scripts/pick_report.py --out="$RUN" --data="$OUT/data" --test_envs="$TEST_ENVS" --start_seed=1000 \
  | tee "$RUN/report.md"
echo "wall time: collect $((t1 - t0)) s, train $((t2 - t1)) s, eval $((t3 - t2)) s (this invocation)"
