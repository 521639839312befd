"""The study grid as steps: one dataset per (task, N, seed, widths), one training run per method on it,
one evaluation per condition of each checkpoint.

What goes into a step's inputs (hence its key) is what changes its results (``inputs.py``; see
``step.py``). The ``--dry-run`` cost model is in ``cost.py``."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, replace
from typing import Any

from ...core.fingerprint import file_fingerprint
from ...datasets.version import DATA_VERSION
from ...factors.registry import get_factor
from ...protocol.conditions import TRAIN_SUITE
from ..run.blocks import with_stop_rule
from ..run.checkpoint import GIVEN_CHECKPOINT, keyed_checkpoint
from ..run.inputs import OWN_FRAMES, CollectInputs, EnvInputs, EvalInputs, TrainInputs
from ..run.recording import RECORD_SETTING
from ..run.step import RUN, Step, versions
from .config import RADII_M, StudyConfig
from .method_config import MethodConfig
from .paths import map_arg_paths, map_policy_paths
from .train_settings import TrainSettings

DEFAULT_WIDTHS = "default"
CURVE_EPOCHS = "epochs"  # the label (``Step.meta``) of a learning curve's evaluation: its checkpoint's epochs


@dataclass(frozen=True)
class Plan:
    steps: tuple[Step, ...]  # in dependency order: every step comes after the steps it depends on

    def of_kind(self, kind: str) -> list[Step]:
        return [s for s in self.steps if s.kind == kind]

    def counts(self) -> Counter:
        return Counter(s.kind for s in self.steps)

    def evaluations(self) -> list[Step]:
        """The grid's evaluations (``results.csv``'s rows): every checkpoint that training ends with, on every
        condition; a learning curve's earlier checkpoints are :meth:`curve_points`."""
        return [s for s in self.of_kind("eval") if CURVE_EPOCHS not in s.meta]

    def curve_points(self) -> list[Step]:
        """The learning curve's evaluations of earlier checkpoints (``train.curve_every``), on ``train``."""
        return [s for s in self.of_kind("eval") if CURVE_EPOCHS in s.meta]

    def given_evaluations(self) -> list[tuple[str, str, EnvInputs]]:
        """(method name, checkpoint, environments) of every given checkpoint's evaluation step (what
        ``checkpoint.check_checkpoints`` checks before any work)."""
        return [
            (s.meta["method"], s.run[GIVEN_CHECKPOINT], EvalInputs.from_dict(s.inputs).environments)
            for s in self.of_kind("eval")
            if GIVEN_CHECKPOINT in s.run
        ]


def widths_label(widths: dict[str, str]) -> str:
    """``{"camera_pos": "medium"}`` -> ``camera_pos=medium``; the main grid -> ``default``."""
    return ",".join(f"{k}={v}" for k, v in sorted(widths.items())) or DEFAULT_WIDTHS


def make_plan(cfg: StudyConfig) -> Plan:
    """Every step of the study, deduplicated by key (a dataset is shared by all methods). A given checkpoint
    (``checkpoint.py``) has evaluations only, in the environments the cell's dataset has (rebuilt from the
    same settings, never collected), at the first seed only (it has no training seed)."""
    variants: list[tuple[dict[str, str], list[str]]] = [({}, cfg.conditions())]
    variants += [({factor: width}, [factor]) for factor, width in cfg.radius_variants()]
    steps: dict[str, Step] = {}
    keyed = {m.checkpoint: keyed_checkpoint(m.checkpoint) for m in cfg.given_methods()}  # each hashed once
    for task in cfg.tasks:
        for widths, conditions in variants:
            for n in cfg.n_train_envs:
                for seed in cfg.seeds:
                    cell = {"task": task, "n_train_envs": n, "seed": seed, "widths": widths_label(widths)}
                    collect = _collect_step(cfg, task, n, seed, widths, cell)
                    if cfg.trained_methods():
                        steps.setdefault(collect.key, collect)
                    for method in cfg.methods:
                        labels = {"method": method.name, **cell}
                        for step in _method_steps(cfg, method, seed, collect, conditions, keyed, labels):
                            steps.setdefault(step.key, step)
    order = {"collect": 0, "train": 1, "eval": 2}
    return Plan(tuple(sorted(steps.values(), key=lambda s: order[s.kind])))


def _method_steps(
    cfg: StudyConfig,
    method: MethodConfig,
    seed: int,
    collect: Step,
    conditions: list[str],
    keyed: dict[str, str],
    labels: dict,
) -> list[Step]:
    """A trained method's training on ``collect``'s dataset and its evaluations; a given checkpoint's
    evaluations in that dataset's environments, at the first seed only."""
    conditions = [TRAIN_SUITE, *conditions]
    if method.trains:
        extras = [
            _extra_collect_step(cfg, method, extra, collect) for extra in method.extra_tasks_for(collect.meta["task"])
        ]
        epochs_over = method.epochs_over if extras and method.epochs_over != OWN_FRAMES else None
        settings = cfg.train_for(method)
        chain = _train_chain(settings, method.policy, seed, collect, labels, extras, epochs_over)
        train = chain[-1]
        curve = [
            _curve_step(cfg, epochs, _trained_at(chain, epochs), collect, labels) for epochs in settings.curve_epochs()
        ]
        evals = [_eval_step(cfg, c, train, collect, labels) for c in conditions]
        return [*extras, *chain, *_stopped(cfg, evals), *curve]
    if seed != cfg.seeds[0]:
        return []
    env = CollectInputs.from_dict(collect.inputs).environments(method.obs)
    return _stopped(cfg, [_given_eval_step(cfg, c, method.checkpoint, keyed, env, labels) for c in conditions])


def _stopped(cfg: StudyConfig, evals: list[Step]) -> list[Step]:
    """A checkpoint's evaluations, as one group under the stopping rule with ``eval.episodes=auto``."""
    return with_stop_rule(evals, cfg.eval.stop_rule()) if cfg.eval.auto else evals


def _collect_step(cfg: StudyConfig, task: str, n: int, seed: int, widths: dict[str, str], cell: dict) -> Step:
    c = cfg.collect
    inputs = CollectInputs(
        task=task,
        n_envs=n,
        seed=seed,
        train_factors=tuple(sorted(cfg.train_factors)),  # each factor has its own RNG: the order changes nothing
        demos=c.demos_for(task),
        cameras=c.cameras,
        image_size=c.image_size,
        use_videos=c.use_videos,
        action_noise=c.action_noise,
        max_episode_steps=c.max_episode_steps,
        n_distractors=c.n_distractors,
        rgb_fraction=c.effective_rgb_fraction,
        widths={"object_pos": c.object_pos_width, **widths},
        data_version=DATA_VERSION,
        versions=versions(),
        family_options=c.family_options_for(task),  # e.g. objects per scene, for the families that read them
        quality=c.other_quality,  # the default is left out: keys as before
    )
    return Step("collect", inputs.to_dict(), (), {**cell, RUN: {"workers": c.workers}})


def _extra_collect_step(cfg: StudyConfig, method: MethodConfig, task: str, collect: Step) -> Step:
    """Another task's dataset in ``collect``'s cell (same N, seed, widths and collection settings): out-of-domain
    data for ``method``. With the default demos it is that task's own dataset in the cell (one key, collected once)."""
    inputs = replace(
        CollectInputs.from_dict(collect.inputs),
        task=task,
        demos=method.extra_demos or cfg.collect.demos_for(task),
        family_options=cfg.collect.family_options_for(task),
    )
    return Step("collect", inputs.to_dict(), (), {**collect.meta, "task": task})


def _train_chain(
    t: TrainSettings,
    policy: dict[str, Any],
    seed: int,
    collect: Step,
    labels: dict,
    extras: list[Step],
    epochs_over: str | None,
) -> list[Step]:
    """The training steps of one method on one dataset: one, or (``train.extends``) one per budget, each after the
    first continuing the one before it (its dependency); the last is the full budget's."""
    chain: list[Step] = []
    for budget in [*t.extends, None]:
        settings = t if budget is None else t.at_budget(budget)
        link = {} if budget is None else {"budget": budget}
        prefix = chain[-1] if chain else None
        chain.append(_train_step(settings, policy, seed, collect, {**labels, **link}, extras, epochs_over, prefix))
    return chain


def _trained_at(chain: list[Step], epochs: float) -> Step:
    """The training of ``chain`` that saves the learning curve's checkpoint at ``epochs``: the first whose budget
    reaches it, so a point at a link's end is that link's last checkpoint, evaluated as soon as the link ends (the
    earlier points are the shorter trainings' own, with their keys)."""
    return next(s for s in chain if epochs <= s.inputs["epochs"])


def _train_step(
    t: TrainSettings,
    policy: dict[str, Any],
    seed: int,
    collect: Step,
    labels: dict,
    extras: list[Step],
    epochs_over: str | None = None,
    prefix: Step | None = None,
) -> Step:
    """Training of one method on one dataset (with ``extras``: merged with other tasks' datasets; the task's
    own comes first in ``deps``, and ``epochs_over`` says what an epoch counts); weight files enter the key by
    content, not by location. ``t``: the method's settings (``StudyConfig.train_for``); ``prefix``: the shorter
    training this one continues (last in ``deps``, its budget as ``extends``: neither there without it)."""
    keyed = t.keyed()  # the settings' part of the key, as the config's check for duplicate methods reads it
    inputs = TrainInputs(
        policy=keyed_policy(policy),
        seed=seed,
        **{**keyed, "extra_args": tuple(keyed_args(keyed["extra_args"]))},  # weight files by content
        versions=versions(),
        epochs_over=epochs_over,
        extends=None if prefix is None else _budget(prefix),
    )
    run = {"policy": policy, "extra_args": list(t.extra_args)}
    deps = (collect.key, *(e.key for e in extras), *((prefix.key,) if prefix else ()))
    return Step("train", inputs.to_dict(), deps, {**labels, RUN: run})


def _budget(train: Step) -> float:
    """A training step's budget: its epochs, or its steps without epochs."""
    inputs = train.inputs
    return inputs["steps"] if inputs["epochs"] is None else inputs["epochs"]


def _eval_step(cfg: StudyConfig, condition: str, train: Step, collect: Step, labels: dict) -> Step:
    """One condition of one checkpoint; threads and recorded episodes do not change results (kept out of the key),
    and ``train`` (the
    dataset's own environments) does not depend on ``n_test_envs``."""
    run = {"threads": cfg.eval.threads, RECORD_SETTING: cfg.eval.record_episodes}
    inputs = _eval_inputs(cfg, condition, labels["task"])
    return Step("eval", inputs.to_dict(), (train.key, collect.key), {**labels, "condition": condition, RUN: run})


def _curve_step(cfg: StudyConfig, epochs: float, train: Step, collect: Step, labels: dict) -> Step:
    """P_T of the learning curve's checkpoint at ``epochs`` (nominal): the ``train`` condition's evaluation with
    that checkpoint, a step of its own (the curve's last point is the grid's own ``train`` evaluation). At the end
    of a shorter training of a chain (``train.extends``) it is that training's own ``train`` evaluation, the key a
    study that trains only that budget gives its last point."""
    step = _eval_step(cfg, TRAIN_SUITE, train, collect, labels)
    inputs = step.inputs
    if epochs != train.inputs["epochs"]:  # a checkpoint before the training's last
        inputs = replace(_eval_inputs(cfg, TRAIN_SUITE, labels["task"]), checkpoint_epochs=epochs).to_dict()
    return Step("eval", inputs, step.deps, {**step.meta, CURVE_EPOCHS: epochs})


def _given_eval_step(
    cfg: StudyConfig, condition: str, checkpoint: str, keyed: dict[str, str], env: EnvInputs, labels: dict
) -> Step:
    """One condition of a given checkpoint: no dependency; the key holds the checkpoint's content hash
    (``keyed``) and the environments (where the checkpoint lies travels in ``run``)."""
    run = {"threads": cfg.eval.threads, RECORD_SETTING: cfg.eval.record_episodes, GIVEN_CHECKPOINT: checkpoint}
    inputs = replace(_eval_inputs(cfg, condition, labels["task"]), checkpoint=keyed[checkpoint], environments=env)
    return Step("eval", inputs.to_dict(), (), {**labels, "condition": condition, RUN: run})


def _eval_inputs(cfg: StudyConfig, condition: str, task: str) -> EvalInputs:
    ev = cfg.eval
    return EvalInputs(
        condition=condition,
        episodes=ev.budget,
        start_seed=ev.start_seed,
        max_episode_steps=ev.max_steps_for(task),
        device=ev.device,
        versions=versions(),
        n_test_envs=None if condition == TRAIN_SUITE else ev.n_test_envs,
        batch_size=ev.batch_size if ev.batch_size > 1 else None,
    )


def _keyed_path(value: str) -> str:
    """A path setting as the key sees it: an existing file by its content hash, anything else as given."""
    return file_fingerprint(value) or value


def keyed_policy(policy: dict[str, Any]) -> dict[str, Any]:
    """Policy settings for the key: every path-like setting naming a file replaced by its content hash."""
    return map_policy_paths(policy, _keyed_path)


def keyed_args(args: list[str]) -> list[str]:
    """``lerobot-train`` flags for the key: path-like values naming a file replaced by its content hash."""
    return map_arg_paths(args, _keyed_path)


def radius_of(widths: str, factor: str) -> float | None:
    """The paper's radius (m) of ``factor`` in a run with ``widths`` (``default`` = the factor's default width)."""
    if widths == DEFAULT_WIDTHS:
        return RADII_M.get(get_factor(factor).default_width)
    parts = dict(p.split("=") for p in widths.split(","))
    return RADII_M.get(parts.get(factor, get_factor(factor).default_width))
