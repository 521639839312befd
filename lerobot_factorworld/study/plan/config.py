"""``factorworld study --config configs/study/<name>.yaml``: the settings of a generalization-gap study.

A study is the grid methods x tasks x N x seeds, each cell trained on its own dataset and evaluated on
the conditions: ``train``, every factor in ``factors``, the ``pairs``, and the radius sweep (camera and
table position sampled, for training and test alike, from radii 0.025 / 0.05 / 0.075 m). Everything is
checked before any work starts: each settings group checks itself (``method_config.py``,
``collect_settings.py``, ``train_settings.py``, ``eval_settings.py``), and :class:`StudyConfig` composes them
and checks what depends on more than one. LeRobot's verdict on the policy settings (``policy_checks.py``) is
:meth:`StudyConfig.check_policies`, asked where a study is run or planned, not where a report reads its config.
"""

from __future__ import annotations

import itertools
import json
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from ...core.io import atomic_write_json
from ...datasets.hub import check_hub_repo_id
from ...envs.lerobot_obs import LEROBOT_METAWORLD_OBS, check_lerobot_task
from ...factors.registry import PAPER_STUDY_FACTORS, WIDTHS, check_task_support, get_factor
from ...families import all_families, condition_family, family_of
from ...protocol.conditions import PAIR_SEPARATOR, condition_name, parse_shift
from ...protocol.sampling import SamplingOptions
from ...tasks import get_task
from ..run.inputs import OWN_FRAMES
from .claim_config import ClaimConfig
from .collect_settings import CollectSettings
from .eval_settings import EvalSettings
from .method_config import MethodConfig, check_extra_task
from .paths import WEIGHTS_SUFFIX, policy_paths, split_flag
from .policy_checks import check_extendable, check_policy
from .train_settings import TrainSettings

ALL_PAIRS = "all"
RADIUS_FACTORS = ("camera_pos", "table_pos")
RADII_M = {"narrow": 0.025, "medium": 0.05, "wide": 0.075}  # the paper's radii (appendix table)


def write_run_config(path: str | Path, settings: dict[str, Any]) -> None:
    """A study's settings as JSON (which YAML reads too) in the one format its folder and docs/results/ use."""
    atomic_write_json(path, settings, indent=1, sort_keys=True, default=str)


# the benchmark dataset a profile's Hub results name (not on the Hub yet)
HUB_BENCHMARK = "lerobot-factorworld/factor-world"


@dataclass
class StudyConfig:
    """A generalization-gap study: the experiment grid and the claims it tests. Every setting here can change
    what a step computes; how the grid runs (workers, executor, dry-run, ...) is :class:`..run.options.RunOptions`,
    and a study's YAML file or command line holds both (:class:`.command.StudyCommand`).

    Args:
        name: Study name (in results and report).
        out_dir: Study folder: ``results.csv``, ``report.md``, plots, and the cached steps (``steps/``).
        tasks: Tasks.
        n_train_envs: The N values (training environments per dataset).
        seeds: Seeds; seed ``s`` samples the training and test environments and seeds training.
        train_factors: Factors varied across the training environments (the paper's seven).
        factors: Single-factor conditions; also the conditions a task family adds (its ``conditions``,
            e.g. held-out phrasings and objects), which stand alone: no pairs, no training factor.
        pairs: Pair conditions: ``[all]`` (every pair of the factors in ``factors``) or a list of ``a+b``.
        radius_factors: Factors of the radius sweep (``camera_pos``, ``table_pos``).
        radius_widths: Widths of the sweep: narrow / medium / wide = radius 0.025 / 0.05 / 0.075 m.
        methods: Methods (policy types and overrides).
        collect: Demonstration settings.
        train: Training settings.
        eval: Evaluation settings.
        claims: The paper's claims this study tests (``claim_config.py``): the report decides each from its
            intervals (``claims.py``). None: the paper's factor ordering over ``factors``.
        finding: The paper's finding this study is one of several studies of (``F2``, ``F8``, ...): its report
            decides its claims together with those of the other studies of the same finding beside its folder,
            with one Holm correction for all of them and shared cells decided once. Empty: this study alone.
        hub_benchmark: The Hub benchmark dataset (``user/name``) a profile's ``.eval_results`` entries name and
            its ``eval.yaml`` describes (``results/eval_results.py``). The default is not on the Hub yet.
    """

    name: str = "study"
    out_dir: str = "outputs/study"
    tasks: list[str] = field(default_factory=lambda: ["door-open"])
    n_train_envs: list[int] = field(default_factory=lambda: [5])
    seeds: list[int] = field(default_factory=lambda: [0])
    train_factors: list[str] = field(default_factory=lambda: list(PAPER_STUDY_FACTORS))
    factors: list[str] = field(default_factory=lambda: list(PAPER_STUDY_FACTORS))
    pairs: list[str] = field(default_factory=list)
    radius_factors: list[str] = field(default_factory=list)
    radius_widths: list[str] = field(default_factory=lambda: list(WIDTHS))
    methods: list[MethodConfig] = field(
        default_factory=lambda: [MethodConfig("rt1_small", {"type": "rt1", "preset": "small"})]
    )
    collect: CollectSettings = field(default_factory=CollectSettings)
    train: TrainSettings = field(default_factory=TrainSettings)
    eval: EvalSettings = field(default_factory=EvalSettings)
    claims: list[ClaimConfig] = field(default_factory=list)
    finding: str = ""
    hub_benchmark: str = HUB_BENCHMARK

    def __post_init__(self) -> None:
        self.methods = [m if isinstance(m, MethodConfig) else MethodConfig(**m) for m in self.methods]
        self.claims = [c if isinstance(c, ClaimConfig) else ClaimConfig(**c) for c in self.claims]
        self.validate()

    # --- derived -----------------------------------------------------------------------------

    def only(self, names: Sequence[str]) -> StudyConfig:
        """This grid with only the methods ``names``: a part of the study run on its own (another machine trains
        one method) and merged with the rest by ``factorworld merge-results``. Their steps keep the keys they have
        in the whole grid (a key holds its own method's settings, never the list of methods); the claims about a
        method left out go too (a claim that names none is the first method's, and a baseline is one)."""
        known = [m.name for m in self.methods]
        unknown = [n for n in names if n not in known]
        if unknown or not names:
            given = ", ".join(unknown) or "(none given)"
            raise ValueError(f"only_methods: unknown method(s) {given}; this study's methods: {', '.join(known)}")
        owned = [c if c.method else replace(c, method=known[0]) for c in self.claims]
        claims = [c for c in owned if c.method in names and c.baseline in (None, *names)]
        return replace(self, methods=[m for m in self.methods if m.name in names], claims=claims)

    def trained_methods(self) -> list[MethodConfig]:
        """The methods the study trains (policy settings): they need the collections and trainings."""
        return [m for m in self.methods if m.trains]

    def given_methods(self) -> list[MethodConfig]:
        """The methods that name an existing checkpoint: evaluated only."""
        return [m for m in self.methods if not m.trains]

    def train_for(self, method: MethodConfig) -> TrainSettings:
        """The training settings ``method`` trains with: the study's ``train`` with the method's own ``train``
        over them (``steps`` clears the study's ``epochs`` and ``curve_every``)."""
        own = dict(method.train)
        if "steps" in own:  # a number of steps: no epochs, so no curve or epochs to extend unless the method asks
            own = {"epochs": None, "curve_every": 0, "extends": [], **own}
        if not own:
            return self.train
        try:
            return replace(self.train, **own)
        except ValueError as err:  # "train.steps must be at least 1, got 0": the method's own settings
            raise ValueError(f"method {method.name!r}: {err}") from None

    def curve_methods(self) -> list[MethodConfig]:
        """The trained methods with a learning curve (their ``train.curve_every``)."""
        return [m for m in self.trained_methods() if self.train_for(m).curve_every]

    def family_conditions(self) -> list[str]:
        """The task families' own conditions listed in ``factors`` (e.g. held-out phrasings / objects)."""
        return [f for f in self.factors if condition_family(f) is not None]

    def shifted_factors(self) -> list[str]:
        """The factors of ``factors`` (without the families' conditions)."""
        return [f for f in self.factors if condition_family(f) is None]

    def pair_conditions(self) -> list[str]:
        if [p.strip() for p in self.pairs] == [ALL_PAIRS]:
            return [condition_name(p) for p in itertools.combinations(self.shifted_factors(), 2)]
        return [condition_name(parse_shift(p)) for p in self.pairs]

    def conditions(self) -> list[str]:
        """The shifted conditions of the main grid (singles, then pairs)."""
        return [*self.factors, *self.pair_conditions()]

    def radius_variants(self) -> list[tuple[str, str]]:
        """(factor, width) runs of the sweep whose width differs from the factor's default (those
        reuse the main grid)."""
        return [
            (factor, width)
            for factor in self.radius_factors
            for width in self.radius_widths
            if width != get_factor(factor).default_width
        ]

    # --- checks ------------------------------------------------------------------------------

    def validate(self) -> None:
        if not self.tasks or not self.n_train_envs or not self.seeds or not self.methods:
            raise ValueError("a study needs at least one task, one N (n_train_envs), one seed and one method")
        self._validate_conditions()
        self._validate_methods()
        for claim in self.claims:
            claim.validate([m.name for m in self.methods], self.tasks, self.shifted_factors(), self.pair_conditions())
        if self.finding and not re.fullmatch(r"[A-Za-z0-9_.-]+", self.finding):
            raise ValueError(f"finding must be a short name such as F8 (letters, digits, _ . -), got {self.finding!r}")
        check_hub_repo_id(self.hub_benchmark, "hub_benchmark")
        for factor in self.radius_factors:
            if factor not in RADIUS_FACTORS:
                raise ValueError(f"the radius sweep applies to {', '.join(RADIUS_FACTORS)}, got {factor!r}")
            if factor not in self.factors:
                raise ValueError(
                    f"radius factor {factor!r} must also be in factors (its narrow radius is the main grid)"
                )
        for width in self.radius_widths:
            if width not in RADII_M:
                raise ValueError(f"unknown radius width {width!r}; valid: {', '.join(RADII_M)}")
        self._validate_family_options()
        if min(self.n_train_envs) < 1 or len(set(self.n_train_envs)) != len(self.n_train_envs):
            raise ValueError(f"n_train_envs must be distinct positive numbers, got {self.n_train_envs}")
        if len(set(self.seeds)) != len(self.seeds):
            raise ValueError(f"seeds must be distinct, got {self.seeds}")
        self._validate_episodes()
        self.train.check_budgets("train")
        for method in self.trained_methods():
            if method.train:
                self.train_for(method).check_budgets(f"method {method.name!r}: train")

    def check_policies(self) -> None:
        """LeRobot's verdict on the trained methods' policy settings. Apart from :meth:`validate`, since importing
        LeRobot's policy configs loads torch (seconds): a study that runs or is planned asks for it
        (:class:`.command.StudyCommand`, the runner), a report of a study that ran reads its config without it."""
        for method in self.trained_methods():
            check_policy(method)
            if self.train_for(method).extends:
                check_extendable(method, self.train_for(method))

    def _validate_conditions(self) -> None:
        """Factors apply to every task and are varied in training; a family's conditions need its tasks."""
        duplicates = sorted({f for f in self.factors if self.factors.count(f) > 1})
        if duplicates:
            raise ValueError(f"factors lists {', '.join(duplicates)} more than once")
        for condition in self.family_conditions():
            condition_family(condition).check_condition(condition, self.tasks)  # "applies to the x family only"
        shifted = self.shifted_factors()
        for task in self.tasks:
            check_task_support(get_task(task), [*self.train_factors, *shifted, *self.radius_factors])
        unknown = [f for f in shifted if f not in self.train_factors]
        if unknown and self.trained_methods():  # a given checkpoint's training is not this study's
            raise ValueError(
                f"factor(s) {unknown} are shifted but not varied in training (train_factors: {self.train_factors})"
            )
        for pair in self.pairs:
            named = [part.strip() for part in pair.split(PAIR_SEPARATOR)]
            if any(condition_family(part) is not None for part in named):
                own = [c for family in all_families() for c in family.conditions]
                raise ValueError(f"pair {pair!r}: the conditions {', '.join(own)} stand alone (list them in factors)")
        for pair in self.pair_conditions():
            if any(f not in shifted for f in pair.split(PAIR_SEPARATOR)):
                raise ValueError(f"pair {pair!r} names a factor that is not in factors {shifted}")

    def _validate_methods(self) -> None:
        """Each method is a valid policy, named once, with settings no other method has (one train key each);
        a given checkpoint is named once per observation, and LeRobot's observation needs Meta-World tasks.
        (Their policy settings are LeRobot's to check: :meth:`check_policies`.)"""
        if any(m.obs == LEROBOT_METAWORLD_OBS for m in self.methods):
            for task in self.tasks:
                check_lerobot_task(get_task(task))  # "the pick family has no LeRobot counterpart"
        names = [m.name for m in self.methods]
        if len(set(names)) != len(names):
            twice = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"method names must be distinct: {', '.join(twice)} given more than once")
        for method in self.trained_methods():
            for task in self.tasks if method.extra_tasks else ():
                check_extra_task(method.name, task, "with extra_tasks, task")
            if method.epochs_over != OWN_FRAMES and self.train_for(method).epochs is None:
                raise ValueError(
                    f"method {method.name!r}: epochs_over={method.epochs_over} says what train.epochs counts; "
                    "set train.epochs instead of train.steps"
                )
        seen: dict[str, str] = {}
        for method in self.trained_methods():
            data = {"extra_tasks": sorted(method.extra_tasks), "extra_demos": method.extra_demos}
            data["epochs_over"] = method.epochs_over
            data["train"] = self.train_for(method).keyed()
            settings = json.dumps({"policy": method.policy, **data}, sort_keys=True)
            if settings in seen:
                raise ValueError(
                    f"methods {seen[settings]!r} and {method.name!r} have the same policy settings {method.policy}, "
                    "training settings and training data: "
                    "they would train one checkpoint; drop one or change its settings"
                )
            seen[settings] = method.name
        given: dict[tuple[str, str], str] = {}
        for method in self.given_methods():
            same = given.setdefault((method.checkpoint, method.obs), method.name)
            if same != method.name:
                raise ValueError(
                    f"methods {same!r} and {method.name!r} name the same checkpoint {method.checkpoint} with the same "
                    f"obs={method.obs}: they would be one evaluation; drop one"
                )

    def _validate_family_options(self) -> None:
        """A family's sampling option (``collect.n_objects``) is set only for tasks of families that read
        it, and within the range ``SamplingOptions`` accepts."""
        for family in all_families():
            for name in family.sampling_options:
                value = getattr(self.collect, name)
                if value is None:
                    continue
                others = [t for t in self.tasks if name not in family_of(t).sampling_options]
                if others:
                    raise ValueError(
                        f"collect.{name} applies to the {family.name} family only, not to {', '.join(others)}"
                    )
                try:
                    SamplingOptions(**{name: value})
                except ValueError as err:
                    raise ValueError(f"collect.{err}") from None

    def missing_weight_files(self) -> list[str]:
        """``method 'x': <setting> <path>`` for every weights file a method names that does not exist."""
        missing = []
        for method in self.methods:
            for name, path in policy_paths(method.policy).items():
                if name.endswith(WEIGHTS_SUFFIX) and not Path(path).is_file():
                    missing.append(f"method {method.name!r}: {name} {path}")
        owners = [("train.extra_args", self.train.extra_args)]
        owners += [
            (f"method {m.name!r}: train.extra_args", m.train["extra_args"])
            for m in self.methods
            if "extra_args" in m.train
        ]
        for owner, args in owners:
            for arg in args:
                flag = split_flag(arg)
                if flag and flag[0].endswith(WEIGHTS_SUFFIX) and not os.path.isfile(flag[1]):
                    missing.append(f"{owner}: {flag[0]} {flag[1]}")
        return missing

    def check_weight_files(self) -> None:
        """Refuse to start when a weights file is missing (weights are never downloaded)."""
        missing = self.missing_weight_files()
        if missing:
            raise FileNotFoundError(
                f"weights file(s) not found: {'; '.join(missing)} (weights are never downloaded: put the files "
                "there or fix the paths, relative to the directory you run from)"
            )

    def _validate_episodes(self) -> None:
        """The episodes fit the study's N (each test environment paired with a training one) and the test
        environments, and the demos cover the N (the evaluation's other checks are ``EvalSettings``'s)."""
        ev = self.eval
        if ev.auto:
            self._validate_auto()
        setting, count = ev.round()
        for n in self.n_train_envs:
            if ev.n_test_envs % n:
                raise ValueError(
                    f"eval.n_test_envs={ev.n_test_envs} must be a multiple of every N (got N={n}), so that each "
                    "test environment is paired with the training environment the same episode sees"
                )
            if count % n:
                raise ValueError(f"{setting} must be a multiple of every N (got N={n})")
        if count % ev.n_test_envs:  # after the N: a count that misses both is told the N first
            raise ValueError(
                f"{setting} must be a multiple of eval.n_test_envs={ev.n_test_envs}, so that every "
                "test environment is visited equally"
            )
        for task in self.tasks if self.trained_methods() else ():  # demos are collected for training only
            if self.collect.demos_for(task) < max(self.n_train_envs):
                raise ValueError(
                    f"{task}: {self.collect.demos_for(task)} demos cannot cover N={max(self.n_train_envs)} environments"
                )

    def _validate_auto(self) -> None:
        """``eval.episodes=auto`` stops each checkpoint's evaluation on its own anytime-valid intervals: refused
        where the study's claims rest on fixed-n intervals that such a stopping makes invalid (its stopping rule
        is ``EvalSettings``'s own check)."""
        why = (
            "eval.episodes=auto stops each checkpoint's evaluation on its own anytime-valid intervals, which "
            "leaves {what} without a valid interval: give eval.episodes a number"
        )
        if len(self.seeds) > 1:
            raise ValueError(why.format(what=f"the claims over seeds {self.seeds} (fixed-n seed-level bootstraps)"))
        if self.claims:
            raise ValueError(why.format(what="the config's claims (decided on fixed-n bootstrap intervals)"))
        if self.curve_methods():
            raise ValueError(why.format(what="the learning curve (fixed-n intervals per checkpoint)"))
        if not self.conditions():
            raise ValueError("eval.episodes=auto stops shifted conditions once decided: list at least one factor")
