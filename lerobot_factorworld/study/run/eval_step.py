"""The ``eval`` step: one condition of one checkpoint (a training's, or a given one) evaluated by LeRobot's
``eval_policy_all`` on the ``factorworld`` env, as ``lerobot-eval`` does; its result holds every episode's success,
stage, length and seed, and the environments' fingerprint. ``eval.episodes=auto`` runs the same session block by
block (``blocks.py``)."""

from __future__ import annotations

import contextlib
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from ...envs.stages import stage_names
from ...families import family_of
from ...protocol.conditions import fingerprint
from ...protocol.coverage import coverage
from .checkpoint import GIVEN_CHECKPOINT, checkpoint_folder
from .context import current
from .device import require_device
from .eval_env import eval_env_config
from .inputs import CollectInputs, EvalInputs
from .recording import MEASURES_KEY, RECORD_SETTING, RECORDED_KEY, EpisodeRecorder, write_recorded
from .result import INPUTS_FILE, read_result
from .step import Step
from .train_schedule import curve_checkpoint


def run_eval(step: Step, folder: Path, deps: list[Path]) -> dict[str, Any]:
    """Evaluate ``step``'s condition once, all its episodes (``worker.RUNNERS``)."""
    session = EvalSession(step, folder, deps)
    inputs = session.inputs
    successes = session.episodes(inputs.start_seed, inputs.episodes)
    return session.result(successes, [inputs.start_seed + i for i in range(len(successes))])


class EvalSession:
    """One condition of one checkpoint, ready to run episodes: its environments, policy and records. A plain
    evaluation runs its episodes once; ``eval.episodes=auto`` (``blocks.py``) runs them block by block."""

    def __init__(self, step: Step, folder: Path, deps: list[Path], reload: bool = False) -> None:
        timings, execution = current()
        with timings.span("imports"):  # paid once per worker process: later steps find them imported
            # Deliberately here: torch and LeRobot's evaluation stack (seconds to import), only in the process
            # that evaluates (planning never needs them).
            import torch  # noqa: PLC0415
            from lerobot.envs.factory import make_env, make_env_pre_post_processors  # noqa: PLC0415

        inputs, run = EvalInputs.from_dict(step.inputs), step.run
        torch.set_num_threads(run.get("threads", 1))
        if inputs.checkpoint is not None:  # a given checkpoint, unchanged since it was planned, in its environments
            checkpoint = str(checkpoint_folder(run[GIVEN_CHECKPOINT], inputs.checkpoint))
            env_cfg = eval_env_config(inputs.environments, None, inputs)
        else:  # trained on a dataset, whose own environments are the training condition
            collect_folder = _dep_of_kind(deps, "collect")
            collect_inputs = CollectInputs.from_dict(json.loads((collect_folder / INPUTS_FILE).read_text())["inputs"])
            train_folder = _dep_of_kind(deps, "train")
            trained = read_result(train_folder)
            checkpoint = trained["checkpoint"]
            if inputs.checkpoint_epochs is not None:  # a learning curve's earlier checkpoint
                saved_at = trained.get("curve", {}).get(str(inputs.checkpoint_epochs))
                if saved_at is None:
                    raise RuntimeError(
                        f"the training saved no checkpoint at {inputs.checkpoint_epochs} epochs ({train_folder})"
                    )
                checkpoint = str(curve_checkpoint(train_folder, saved_at))
            env_cfg = eval_env_config(collect_inputs, read_result(collect_folder)["root"], inputs)
        self.inputs, self.folder, self.timings, self.env_cfg = inputs, folder, timings, env_cfg
        self.checkpoint, self.task = checkpoint, env_cfg.task_names[0]
        self.configs = env_cfg.suites(self.task)[inputs.condition]
        # reload: every block starts from the RNG state a fresh load leaves (blocks.py), so a block's outcomes
        # depend on its seeds only; a plain evaluation loads once, cached across a grouped worker's conditions
        self.cached = reload or execution == "grouped"
        self.reload = reload
        self._load()
        with timings.span("env_build"):
            self.env_pre, self.env_post = make_env_pre_post_processors(env_cfg=env_cfg, policy_cfg=self.policy_cfg)
            self.envs = make_env(env_cfg, n_envs=inputs.batch_size or 1, use_async_envs=False)
        # Stages, lengths and the first episodes' frames, from the envs' own observer hook (instances only).
        recorded = range(inputs.start_seed, inputs.start_seed + min(run.get(RECORD_SETTING, 0), inputs.episodes))
        self.recorder = EpisodeRecorder(frozenset(recorded), family_of(self.task).episode_measures)

    def _load(self) -> None:
        with self.timings.span("policy_load"):
            self.policy_cfg, self.policy, self.preprocessor, self.postprocessor = _load_policy(
                self.checkpoint, self.env_cfg, self.inputs.device, self.inputs.start_seed, cached=self.cached
            )

    def episodes(self, start_seed: int, n: int) -> list[bool]:
        """Run ``n`` episodes reset with seeds ``start_seed`` on (LeRobot's ``eval_policy_all``); their successes."""
        import torch  # noqa: PLC0415 - imported by __init__ already (seconds the first time)
        from lerobot.scripts.lerobot_eval import eval_policy_all  # noqa: PLC0415 - LeRobot's evaluation stack

        if self.reload:
            self._load()
        timings = self.timings
        # timed, unchanged (each part exclusive of the parts inside it): scene compilation and rendering, the
        # environments' resets and steps (on these env instances), the policy's actions, the rest of LeRobot's rollout
        with contextlib.ExitStack() as stack:
            for env in _factorworld_envs(self.envs):
                env.episode_observer = self.recorder  # stages, lengths and the first episodes' frames
                env.timer = timings.span  # scene compilation and rendering, from the env's own hook
                stack.enter_context(timings.wrap(env, "reset", "env_reset"))
                stack.enter_context(timings.wrap(env, "step", "env_step"))
            stack.enter_context(timings.wrap(self.policy, "select_action", "policy"))
            stack.enter_context(timings.span("rollout_other"))
            stack.enter_context(torch.no_grad())
            info = eval_policy_all(
                self.envs,
                self.policy,
                self.env_pre,
                self.env_post,
                self.preprocessor,
                self.postprocessor,
                n_episodes=n,
                max_episodes_rendered=0,
                start_seed=start_seed,
            )
        return [bool(s) for s in info["per_task"][0]["metrics"]["successes"]]

    def result(
        self,
        successes: list[bool],
        seeds: list[int],
        stages: list[str] | None = None,
        lengths: list[int] | None = None,
        tracked: list[str] | None = None,
        measures: list[dict[str, float]] | None = None,
    ) -> dict[str, Any]:
        """The step's result for these episodes (``stages``, ``lengths`` and the stages ``tracked``: blocks', read
        back from their cache; else this run's, which tracks the task's stages of now)."""
        with self.timings.span("records"):
            recorder, configs, folder = self.recorder, self.configs, self.folder
            cover = coverage(seeds, len(configs))
            width = self.env_cfg.sampling.widths.get("object_pos")
            result = {
                "env_steps": self.timings.calls.get("env_step", 0),  # the cost model's unit (not a result)
                "condition": self.inputs.condition,
                "successes": successes,
                "seeds": seeds,
                "stages": stages or of_seeds(recorder.stages, seeds),  # the furthest stage of every episode
                "stage_names": tracked or list(stage_names(self.task)),  # the stages that were tracked
                "lengths": lengths or of_seeds(recorder.lengths, seeds),  # steps of every episode
                "n_envs": len(configs),
                "envs_visited": cover.visited,
                "equal_visits": cover.equal,
                "fingerprint": fingerprint(configs, width),
                "checkpoint": self.checkpoint,
                "policy_type": self.policy_cfg.type,  # a given checkpoint's type is known from it only
            }
            if recorder.measure_keys:  # the family's per-episode measures (e.g. how close the gripper came)
                result[MEASURES_KEY] = measures if measures is not None else of_seeds(recorder.measures, seeds)
            if recorder.frames:  # the recorded episodes' frames as videos (not results: they change no number)
                result[RECORDED_KEY] = write_recorded(recorder, seeds, folder)
            family = family_of(self.task)
            if family.content_key:  # what every episode asked for (e.g. instruction, named object), for breakdowns
                result[family.content_key] = family.episode_records(configs, seeds, width)
        return result


def _factorworld_envs(envs: dict) -> Iterator[Any]:
    """The Factor World envs of LeRobot's ``{suite: {task_id: vector env}}`` (synchronous, in this process)."""
    for suite in envs.values():
        for vector_env in suite.values():
            for env in vector_env.envs:
                yield env.unwrapped


def of_seeds[T](recorded: dict[int, T], seeds: list[int]) -> list[T]:
    """What was recorded for the episodes reset with ``seeds``, in their order; every one must have ended."""
    missing = [seed for seed in seeds if seed not in recorded]
    if missing:
        raise RuntimeError(f"nothing recorded at the end of the episode(s) of seed(s) {missing}: they never ended")
    return [recorded[seed] for seed in seeds]


# The policy loaded by the last evaluation of this (``grouped``) worker, with the RNG state right after
# loading it: the next condition of the same checkpoint starts from exactly that state.
_LOADED: dict[tuple, tuple] = {}


def _load_policy(checkpoint: str, env_cfg, device: str, start_seed: int, cached: bool) -> tuple:
    """(policy config, policy, preprocessor, postprocessor) of ``checkpoint``, seeded with ``start_seed`` before loading
    as ``lerobot-eval`` does. ``cached``: reuse the one this process loaded last for the same checkpoint,
    device and seed, with the RNG state restored to what it was right after loading (what a fresh load
    would leave), so every condition computes what it computes on its own."""
    # Deliberately here: LeRobot's policy stack (seconds to import), only in the process that evaluates.
    from lerobot.configs.policies import PreTrainedConfig  # noqa: PLC0415
    from lerobot.policies.factory import make_policy, make_pre_post_processors  # noqa: PLC0415
    from lerobot.utils.import_utils import register_third_party_plugins  # noqa: PLC0415
    from lerobot.utils.random_utils import get_rng_state, set_rng_state, set_seed  # noqa: PLC0415

    key = (checkpoint, device, start_seed, _mtime(checkpoint))
    if cached and key in _LOADED:
        *loaded, state = _LOADED[key]
        set_rng_state(state)
        return tuple(loaded)
    _LOADED.clear()
    register_third_party_plugins()  # as lerobot-eval does: Factor World's env and policy types, and any other plugin
    policy_cfg = PreTrainedConfig.from_pretrained(checkpoint)
    policy_cfg.pretrained_path = Path(checkpoint)
    policy_cfg.device = require_device("eval.device", device)
    set_seed(start_seed)
    policy = make_policy(cfg=policy_cfg, env_cfg=env_cfg)
    preprocessor, postprocessor = make_pre_post_processors(
        policy_cfg=policy_cfg,
        pretrained_path=checkpoint,
        preprocessor_overrides={"device_processor": {"device": str(policy_cfg.device)}},
    )
    if cached:
        _LOADED[key] = (policy_cfg, policy, preprocessor, postprocessor, get_rng_state())
    return policy_cfg, policy, preprocessor, postprocessor


def _mtime(path: str) -> int:
    weights = Path(path) / "model.safetensors"
    return weights.stat().st_mtime_ns if weights.is_file() else 0


def _dep_of_kind(deps: list[Path], kind: str) -> Path:
    return next(d for d in deps if d.parent.name == kind)
