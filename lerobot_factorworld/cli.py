"""``factorworld`` command line: ``factorworld <command> [--key=value ...]`` (draccus-parsed configs).

Commands:
    tasks           list the tasks and their instructions
    factors         the factors, their ranges, and the task x factor support matrix
    cameras         the scene cameras
    sample          sample N environment configurations and save them as JSON
    contact-sheet   render a task under every factor (PNG)
    collect         scripted demos -> LeRobotDataset with per-episode factor values (resumable)
    rt1-presets     the RT-1 presets and their parameter counts
    study           the generalization-gap study: collect, train, evaluate, report (--config=NAME or FILE.yaml, --dry-run,
                    --report-only: the report of the steps finished so far)
    configs         the study configs that ship with the package (--config=NAME) and their --dry-run cost
    profile         an existing checkpoint under every factor, written as a study (--policy.path=DIR --task=TASK)
    report          regenerate a study's report.md and plots from its results.csv alone (--results=CSV)
    compare-gaps    one factor's gap in two studies and their difference (--first=DIR --second=DIR --factor=F --task=T)
    compare-curves  two studies' learning curves at the checkpoints they share, and their difference (--first=DIR --second=DIR)
    compare-reruns  does a rerun land within the intervals of the results it repeats (--first=DIR --rerun=DIR)
    merge-results   a study made in parts (other machines, sessions) as one results.csv (--into=DIR --add=[DIR])
    pack            what a study needs to go on on another machine, copied into a folder (--study=DIR --out=DIR)
    unpack          a pack put into a study folder, checked first (--pack=DIR --study=DIR)
    sync-docs       regenerate the committed reports under docs/results and the docs tables fenced from them (--check)

Every command reads its settings with :func:`lerobot_factorworld.core.settings.parse_config` (draccus +
the config's ``__post_init__`` validation), so a bad setting ends in one ``error: ...`` line naming the
valid choices (exit status 2) before any work starts; see that module for how to add a command.
"""

from __future__ import annotations

import gc
import sys
import typing
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from .contact_sheet import ContactSheetConfig, render_contact_sheet
from .core.checks import check_at_least, check_folder_target, check_input_file, check_output_file, check_seed
from .core.errors import is_refusal, write_traceback
from .core.settings import CONFIG_PATH_FLAG, SettingError, one_line, parse_config
from .core.splits import check_split
from .factors.registry import FACTORS, PAPER_STUDY_FACTORS, check_factors, support_matrix_markdown
from .factors.values import save_configs
from .protocol.sampling import SamplingOptions, sample_configs
from .scene.cameras import CAMERAS
from .study.plan.named import resolve_study_config, study_names
from .tasks import TASKS, check_tasks

if TYPE_CHECKING:  # the study stack imports LeRobot: only where a command needs it
    from .study.runner import StudyOutcome

SETTING_ERROR_STATUS = 2  # like argparse: the command line was wrong, nothing was done
FAILURE_STATUS = 1  # the settings were valid but the work was refused or failed
INTERNAL_ERROR_STATUS = 70  # a bug (sysexits' EX_SOFTWARE): the traceback is in a log file


@dataclass
class SampleConfig:
    """``factorworld sample``: N training (or eval) environments of a task.

    Attributes:
        task: Task name.
        n: Number of environments.
        seed: Sampling seed.
        split: ``train`` or ``eval`` asset split.
        factors: Factors to vary (default: the paper's seven).
        out: JSON file to write (nothing is written when empty).
        sampling: How factor values are drawn, as for ``collect`` (``--sampling.asset_split=variant``,
            ``--sampling.texture_folder=...``, ``--sampling.n_distractors=2``, ...).
    """

    task: str = "pick-place"
    n: int = 5
    seed: int = 0
    split: str = "train"
    factors: list[str] = field(default_factory=list)
    out: str = ""
    sampling: SamplingOptions = field(default_factory=SamplingOptions)

    def __post_init__(self) -> None:
        (self.task,) = check_tasks([self.task])
        check_at_least("n", self.n, 1)
        check_seed(self.seed)
        check_split(self.split)
        check_factors(self.factors or PAPER_STUDY_FACTORS, [self.task])
        if self.out:
            check_output_file(self.out, "out")


def no_settings(command: str, args: list[str]) -> None:
    if any(arg not in ("-h", "--help") for arg in args):
        raise SettingError(f"factorworld {command} takes no settings, got {' '.join(args)}")


def cmd_tasks(args: list[str]) -> None:
    no_settings("tasks", args)
    for task in TASKS.values():
        print(f"{task.name:28s} {task.gym_id:40s} {task.instruction}")


def cmd_factors(args: list[str]) -> None:
    no_settings("factors", args)
    print("| factor | paper name | kind | visual | ranges |\n|---|---|---|---|---|")
    for spec in FACTORS.values():
        ranges = "; ".join(f"{w}: {list(lo)} .. {list(hi)}" for w, (lo, hi) in spec.ranges.items()) or spec.asset_kind
        print(f"| {spec.name} | {spec.title} | {spec.kind} | {'yes' if spec.visual else 'no'} | {ranges} |")
    print("\nSupport matrix (— = the factor cannot apply to the task; requesting it raises an error):\n")
    print(support_matrix_markdown())
    print("\nPer-task limits (where the task's scripted expert stays >= 90% successful; ranges are clipped to them):\n")
    for task in TASKS.values():
        for name, (low, high) in task.limits:
            print(f"- {task.name}: {name} in {list(low)} .. {list(high)}")


def cmd_cameras(args: list[str]) -> None:
    no_settings("cameras", args)
    for cam in CAMERAS.values():
        print(f"{cam.name:8s} pos={cam.pos} target={cam.target} fovy={cam.fovy}")


def cmd_sample(args: list[str]) -> None:
    cfg = parse_config(SampleConfig, args, "sample")
    configs = sample_configs(cfg.task, cfg.n, cfg.seed, cfg.split, cfg.factors or PAPER_STUDY_FACTORS, cfg.sampling)
    for config in configs:
        print(config)
    if cfg.out:
        print(f"wrote {save_configs(configs, cfg.out)}")


def cmd_contact_sheet(args: list[str]) -> None:
    cfg = parse_config(ContactSheetConfig, args, "contact-sheet")
    print(f"wrote {render_contact_sheet(cfg)}")


def cmd_collect(args: list[str]) -> None:
    from .datasets.collect import CollectConfig, collect  # noqa: PLC0415  imports LeRobot (~2.5 s): only when collecting

    cfg = parse_config(CollectConfig, args, "collect")
    report = collect(cfg)
    print(f"wrote {report.episodes} episodes ({report.frames} frames) to {report.root} in {report.seconds:.1f} s")
    for env, count in report.failures.items():
        print(f"  {env}: {count} failed attempt(s) discarded")


def cmd_rt1_presets(args: list[str]) -> None:
    no_settings("rt1-presets", args)
    from .policies.rt1.presets import preset_table  # noqa: PLC0415  imports torch and LeRobot (~4 s)

    print(preset_table())


STUDY_FLAG_ALIASES = {
    "--config": "--config_path",
    "--dry-run": "--dry_run=true",
    "--strict": "--strict=true",
    "--rerun-stale": "--rerun_stale=true",
    "--report-only": "--report_only=true",
}


def cmd_study(args: list[str]) -> None:
    # LeRobot and torch (~4 s): `factorworld tasks` and friends stay instant
    from .study.plan.command import StudyCommand  # noqa: PLC0415
    from .study.runner import inspect_study, report_study, run_study  # noqa: PLC0415

    command = "factorworld study " + " ".join(args)
    cfg = parse_config(StudyCommand, _study_args(args), "study")
    study, options = cfg.grid(), cfg.options()
    if options.inspects:  # --dry-run, --profile, --fit_cost: nothing runs
        print(inspect_study(study, options))
        return
    if options.report_only:  # nothing runs: the outputs of the steps finished so far
        outcome = report_study(study, options, command)
        finished = ", ".join(f"{n} {kind}" for kind, n in outcome.cached.items())
        print(
            f"finished so far: {finished}; wrote {outcome.results}, {outcome.report} and {len(outcome.plots)} plot(s)"
        )
        return
    _report_outcome(run_study(study, options, command=command))


def cmd_profile(args: list[str]) -> None:
    # LeRobot's env config (~4 s): only when this command runs
    from .study.plan.policy_profile import ProfileConfig  # noqa: PLC0415
    from .study.runner import inspect_study, run_study  # noqa: PLC0415

    command = "factorworld profile " + " ".join(args)
    cfg = parse_config(ProfileConfig, _study_args(args), "profile")
    study, options = cfg.study(), cfg.options()
    if cfg.dataset_root:
        print(
            f"train: the {study.n_train_envs[0]} training environment(s) of dataset {cfg.dataset_root} "
            f"(seed {study.seeds[0]}, varying {', '.join(study.train_factors) or 'no factor'})"
        )
    if options.inspects:
        print(inspect_study(study, options))
        return
    _report_outcome(run_study(study, options, command=command))


def _report_outcome(outcome: StudyOutcome) -> None:
    """What a study (or a profile) did, in a few lines; failed steps on stderr and a failure status."""
    ran = ", ".join(f"{n} {kind}" for kind, n in outcome.ran.items())
    cached = ", ".join(f"{n} {kind}" for kind, n in outcome.cached.items())
    print(f"ran {ran}; cached {cached}")
    if outcome.set_aside:
        print(f"redid {len(outcome.set_aside)} step(s) made by other code; their old folders end in .stale-<commit>")
    print(f"wrote {outcome.results} (and episodes.parquet), {outcome.report} and {len(outcome.plots)} plot(s)")
    if outcome.failed:
        for label, error in outcome.failed.items():
            print(f"failed: {label}: {one_line(error)[:300]}", file=sys.stderr)
        _fail(
            RuntimeError(
                f"{len(outcome.failed)} step(s) failed and {outcome.skipped} were skipped (errors in "
                f"{outcome.study_dir}/steps/*/*/error.txt); rerun the same command to retry them"
            ),
            FAILURE_STATUS,
        )


def _study_args(args: list[str]) -> list[str]:
    """The study's command line for draccus: flag aliases spelled out, and ``--config NAME`` (or ``=NAME``, or
    ``--config_path``) as the YAML file it names."""
    out, i = [], 0
    while i < len(args):
        name, sep, value = args[i].partition("=")
        if name in ("--config", CONFIG_PATH_FLAG) and not sep and i + 1 < len(args):
            name, sep, value = name, "=", args[i + 1]
            i += 1
        if name in ("--config", CONFIG_PATH_FLAG) and sep:
            out.append(f"{CONFIG_PATH_FLAG}={_study_config(value)}")
        else:
            out.append(STUDY_FLAG_ALIASES.get(args[i], args[i]))
        i += 1
    return out


def _study_config(value: str) -> str:
    """A study config's file: a path, or the name of one that ships with the package (``quick``)."""
    try:
        return resolve_study_config(value)
    except ValueError as err:
        raise SettingError(str(err)) from None


def cmd_configs(args: list[str]) -> None:
    """The packaged study configs by name, each with its ``--dry-run`` estimate on this machine's kind (2 cores)."""
    no_settings("configs", args)
    # the study's config checks its policies with LeRobot (~4 s): only when this command runs
    from .study.plan.command import StudyCommand  # noqa: PLC0415
    from .study.plan.cost import estimate  # noqa: PLC0415
    from .study.plan.grid import make_plan  # noqa: PLC0415

    print(f"{'name':40s} {'steps':>6s} {'2 cores':>8s} {'1 GPU':>7s}  (--dry-run's estimates, from nothing cached)")
    for name in study_names():
        cfg = parse_config(StudyCommand, [f"{CONFIG_PATH_FLAG}={resolve_study_config(name)}"], "study")
        plan = make_plan(cfg.grid())
        cpu, gpu = list(estimate(plan, plan.steps, cfg.execution).values())[:2]
        print(f"{name:40s} {len(plan.steps):6d} {cpu:7.1f}h {gpu:6.1f}h")


@dataclass
class ReportConfig:
    """``factorworld report``: a study's ``report.md`` and plots regenerated from its ``results.csv`` (nothing
    is run, no step folder is read).

    Attributes:
        results: The study's ``results.csv``.
        config: The study's config YAML, or a packaged study's name (also ``--config_path``); default: the config
            next to ``results``.
        out: Folder to write ``report.md`` and the plots into, with copies of ``results.csv``, the config (as
            ``config.yaml``) and the task families' CSV files; default: the folder of ``results``.
    """

    results: str = ""
    config: str = ""
    out: str = ""

    def __post_init__(self) -> None:
        if not self.results:
            raise ValueError("factorworld report needs --results=PATH/results.csv")
        check_input_file(self.results, "results")
        if self.config:  # a path, or a packaged study's name (learning/rt1)
            self.config = resolve_study_config(self.config)
        if self.out:
            check_folder_target(self.out, "out")


def cmd_report(args: list[str]) -> None:
    # the report's stack (the study's config, statistics, plots: ~2 s; no LeRobot, whose policy checks a report
    # skips): only when this command runs
    from .study.report.write import regenerate_report  # noqa: PLC0415

    cfg = parse_config(ReportConfig, _report_args(args), "report")
    report, plots = regenerate_report(cfg.results, cfg.config or None, cfg.out or None)
    print(f"wrote {report} and {len(plots)} plot(s)")


def _report_args(args: list[str]) -> list[str]:
    """``--config_path`` names the study's config here, not settings of the command (draccus's meaning)."""
    out, i = [], 0
    while i < len(args):
        name, sep, value = args[i].partition("=")
        if name == CONFIG_PATH_FLAG and not sep and i + 1 < len(args):
            out.append(f"--config={args[i + 1]}")
            i += 2
            continue
        out.append(f"--config={value}" if name == CONFIG_PATH_FLAG else args[i])
        i += 1
    return out


@dataclass
class CompareGapsConfig:
    """``factorworld compare-gaps``: one factor's gap in two studies (each one method on one task, at one N) and
    their difference, each with its seed-level bootstrap 95% interval, over the training seeds both hold
    (``study/results/compare.py``).

    Attributes:
        first: A study folder (or its ``results.csv``).
        second: Another study folder (or its ``results.csv``).
        factor: The shifted condition, e.g. ``object_texture``.
        task: The task on both sides.
        method: The method on both sides (the first's, when ``second_method`` is given).
        second_method: The second study's method, if another.
        n_train_envs: N on both sides (needed where a study has several).
    """

    first: str = ""
    second: str = ""
    factor: str = ""
    task: str = ""
    method: str = "bc"
    second_method: str | None = None
    n_train_envs: int | None = None

    def __post_init__(self) -> None:
        for name in ("first", "second", "factor", "task"):
            if not getattr(self, name):
                raise ValueError(f"compare-gaps needs --{name}")
        for name in ("first", "second"):
            check_input_file(_results_file(getattr(self, name)), name)


def _results_file(folder_or_csv: str) -> str:
    from .study.results.rows import RESULTS_FILE  # noqa: PLC0415 - the study stack loads only for the commands that read one

    path = Path(folder_or_csv)
    return str(path / RESULTS_FILE if path.is_dir() else path)


def cmd_compare_gaps(args: list[str]) -> None:
    # the study's statistics (numpy only, but through the study package): only when this command runs
    from .study.results.compare import Side, comparison_lines  # noqa: PLC0415
    from .study.results.rows import read_results  # noqa: PLC0415

    cfg = parse_config(CompareGapsConfig, args, "compare-gaps")
    sides = (
        Side(cfg.method, cfg.task, cfg.n_train_envs),
        Side(cfg.second_method or cfg.method, cfg.task, cfg.n_train_envs),
    )
    first, second = (read_results(_results_file(p)) for p in (cfg.first, cfg.second))
    try:
        lines = comparison_lines((cfg.first, first), (cfg.second, second), cfg.factor, sides)
    except ValueError as err:  # a method, task or factor the studies lack: the command line was wrong
        raise SettingError(str(err)) from None
    print("\n".join(lines))


@dataclass
class CompareCurvesConfig:
    """``factorworld compare-curves``: two studies' learning curves at the checkpoints they share, each P_T with
    its Wilson 95% interval and their difference with Newcombe's (``study/results/compare_curves.py``): whether a
    controlled run (one setting changed in a curve's recipe) moved P_T.

    Attributes:
        first: A study folder (or a committed ``docs/results/<study>``) holding ``curve.csv``.
        second: Another.
        match: Which checkpoints face each other: ``epochs`` (the same nominal epochs) or ``steps`` (the nearest
            gradient step, within 5%: a run on twice the demos reaches a budget in half the epochs).
        method: The first curve's method (default: its only one); also the second's unless ``second_method``.
        second_method: The second curve's method, if another.
        task: The task on both sides (default: each curve's only one).
        family: The first curve's epochs declared beforehand as one finding (e.g. ``[64,80,96]``): only they are
            compared, each difference's interval Bonferroni-corrected over them (at 1 - 0.05/k), and a line says
            where the finding is resolved. Default: every matched point, each at 95% on its own.
    """

    first: str = ""
    second: str = ""
    match: str = "epochs"
    method: str | None = None
    second_method: str | None = None
    task: str | None = None
    family: list[float] | None = None

    def __post_init__(self) -> None:
        from .study.results.compare_curves import MATCHES  # noqa: PLC0415 - the study stack loads only for this command
        from .study.results.curve import CURVE_FILE  # noqa: PLC0415 - as above

        for name in ("first", "second"):
            if not getattr(self, name):
                raise ValueError(f"compare-curves needs --{name}=<study folder holding {CURVE_FILE}>")
            check_input_file(str(Path(getattr(self, name)) / CURVE_FILE), name)
        if self.match not in MATCHES:
            raise ValueError(f"unknown match {self.match!r}; valid: {', '.join(MATCHES)}")


def cmd_compare_curves(args: list[str]) -> None:
    # the study's config and statistics (a report's stack, no LeRobot): only when this command runs
    from .study.report.write import config_next_to, load_config  # noqa: PLC0415
    from .study.results.compare_curves import CurveSide, curve_comparison_lines  # noqa: PLC0415
    from .study.results.curve import CURVE_FILE, read_curve  # noqa: PLC0415

    cfg = parse_config(CompareCurvesConfig, args, "compare-curves")
    folders = [Path(cfg.first), Path(cfg.second)]
    seeds = {load_config(config_next_to(Path(_results_file(str(folder))))).eval.start_seed for folder in folders}
    sides = [
        CurveSide(str(folders[0]), read_curve(folders[0] / CURVE_FILE), cfg.method, cfg.task),
        CurveSide(str(folders[1]), read_curve(folders[1] / CURVE_FILE), cfg.second_method or cfg.method, cfg.task),
    ]
    try:
        print("\n".join(curve_comparison_lines(*sides, match=cfg.match, paired=len(seeds) == 1, family=cfg.family)))
    except ValueError as err:  # a method, task or budget the curves lack: the command line was wrong
        raise SettingError(str(err)) from None


@dataclass
class CompareRerunsConfig:
    """``factorworld compare-reruns``: every evaluation step two runs both made (same key), per cell the first
    run's successes with its Wilson 95% interval, the rerun's, whether the rerun lies within it and its gap within
    the first's paired interval, and (with ``episodes.parquet`` on both sides) how many episodes end alike. Exit
    status 1 when a cell lies outside (``study/results/rerun.py``).

    Attributes:
        first: The first run's folder (holds ``results.csv``).
        rerun: The rerun's folder.
    """

    first: str = ""
    rerun: str = ""

    def __post_init__(self) -> None:
        for name in ("first", "rerun"):
            if not getattr(self, name):
                raise ValueError(f"compare-reruns needs --{name}")
            folder = Path(getattr(self, name))
            if not folder.is_dir():
                raise FileNotFoundError(f"{name} {folder} is not a study folder")
            check_input_file(_results_file(str(folder)), name)


def cmd_compare_reruns(args: list[str]) -> None:
    # reading episodes.parquet and the study's statistics: only when this command runs
    from .study.results.episodes import EPISODES_FILE, read_episodes  # noqa: PLC0415
    from .study.results.rerun import compare_reruns, rerun_lines  # noqa: PLC0415
    from .study.results.rows import read_results  # noqa: PLC0415

    cfg = parse_config(CompareRerunsConfig, args, "compare-reruns")
    folders = [Path(cfg.first), Path(cfg.rerun)]
    episodes = [read_episodes(f / EPISODES_FILE) if (f / EPISODES_FILE).is_file() else [] for f in folders]
    found = compare_reruns(*(read_results(_results_file(str(f))) for f in folders), *episodes)
    print("\n".join(rerun_lines(found)))
    if found.within != len(found.cells):
        raise SystemExit(FAILURE_STATUS)


@dataclass
class MergeResultsConfig:
    """``factorworld merge-results``: a study made in parts (other machines, sessions or commits) as one
    ``results.csv`` and ``episodes.parquet`` in ``into``; every row keeps the commit that made it, a step in two
    parts must hold the same numbers (``study/results/merge.py``). Then ``factorworld report`` renders the whole.

    Attributes:
        into: The study folder to merge into (holds ``results.csv`` and the study's config).
        add: Folders of the other parts (each holds ``results.csv``).
        config: The study's config, a path or a packaged study's name (default: the one next to ``into``'s
            ``results.csv``).
        drop_unplanned: Leave out the rows (and their episodes and curve points) of steps the config no longer
            plans, e.g. a method whose training budget changed, instead of refusing them; each dropped row is
            listed. A part none of whose rows the config plans is still refused (a wrong config).
    """

    into: str = ""
    add: list[str] = field(default_factory=list)
    config: str = ""
    drop_unplanned: bool = False

    def __post_init__(self) -> None:
        if not self.into or not self.add:
            raise ValueError("merge-results needs --into=<study folder> and --add=[<folder>, ...]")
        for name, folder in [("into", self.into), *(("add", f) for f in self.add)]:
            if not Path(folder).is_dir():
                raise FileNotFoundError(f"{name} {folder} is not a study folder")
            check_input_file(_results_file(folder), name)
        if self.config:  # a path, or a packaged study's name
            self.config = resolve_study_config(self.config)


def cmd_merge_results(args: list[str]) -> None:
    # the study's config and plan, and the report (a report's stack, no LeRobot): only when this command runs
    from .study.plan.grid import make_plan  # noqa: PLC0415
    from .study.report.write import config_next_to, load_config  # noqa: PLC0415
    from .study.results.episodes import EPISODES_FILE  # noqa: PLC0415
    from .study.results.merge import cell_label, merge_results  # noqa: PLC0415

    cfg = parse_config(MergeResultsConfig, args, "merge-results")
    into = Path(cfg.into)
    config = Path(cfg.config) if cfg.config else config_next_to(Path(_results_file(cfg.into)))
    study = load_config(config)
    merged = merge_results(
        into, [Path(f) for f in cfg.add], make_plan(study), study=study.name, drop_unplanned=cfg.drop_unplanned
    )
    for row in merged.dropped:
        print(f"dropped {row['step']} ({cell_label(row)}): not in the study's plan")
    for note in merged.notes:
        print(note)
    written, added = merged.written, merged.added
    results, others = written[0], [str(path) for path in written[1:]]
    no_episodes = all(path.name != EPISODES_FILE for path in written)
    print(
        f"wrote {results}"
        + (f" and {', '.join(others)}" if others else "")
        + (f" (no {EPISODES_FILE}: not every part has one)" if no_episodes else "")
    )
    # the folder's own config is refreshed by the report, so a config given here is what the report needs too
    given = f" --config={cfg.config}" if cfg.config else ""
    print(f"added {added} evaluation(s); render it with: factorworld report --results={results}{given}")


@dataclass
class PackConfig:
    """``factorworld pack``: what a rerun of a study on another machine needs to go on from where it is, copied into
    a folder (``study/run/pack.py``: datasets, older optimizer states and unfinished evaluations are left out).
    Works on a running study too: a training's newest save is copied whole.

    Attributes:
        study: The study's folder (its ``out_dir``).
        out: The pack's folder: a new one, or an older pack, replaced once the new one is complete.
    """

    study: str = ""
    out: str = ""

    def __post_init__(self) -> None:
        if not self.study or not self.out:
            raise ValueError("factorworld pack needs --study=STUDY_DIR --out=PACK_DIR")
        check_folder_target(self.out, "out")
        # the pack's module imports MetaWorld's task registry (through run/blocks.py: about a second)
        from .study.run.pack import check_pack_target  # noqa: PLC0415

        check_pack_target(Path(self.study), Path(self.out))


def cmd_pack(args: list[str]) -> None:
    # as in PackConfig: the pack's imports, only when this command runs
    from .study.run.pack import pack  # noqa: PLC0415

    cfg = parse_config(PackConfig, args, "pack")
    packed = pack(cfg.study, cfg.out)
    print(f"packed {packed.files} file(s), {packed.size / 1e6:.1f} MB, into {packed.folder}")
    for rel in packed.trainings:
        print(f"  training in progress, carried with its newest save: {rel}")
    for rel in packed.linked:
        print(f"  left out, linked from another study (reuse_from; pack that study): {rel}")
    if packed.unfinished:
        print(
            f"  left out {len(packed.unfinished)} unfinished step(s): they start over where the study runs next "
            "(an episodes: auto group from its finished blocks, which are carried)"
        )
    print(
        f"go on elsewhere: factorworld unpack --pack={packed.folder} --study={cfg.study}, then the same study command"
    )


@dataclass
class UnpackConfig:
    """``factorworld unpack``: a pack's files put into a study folder, every file checked before anything is
    written; a file already there must be the same (nothing is replaced).

    Attributes:
        pack: The pack's folder (written by ``factorworld pack``).
        study: The study folder to fill (made if absent; the study config's ``out_dir``); default: the folder the
            pack was made from, as it was named there.
    """

    pack: str = ""
    study: str = ""

    def __post_init__(self) -> None:
        if not self.pack:
            raise ValueError("factorworld unpack needs --pack=PACK_DIR (and --study=STUDY_DIR)")
        # as in PackConfig: the pack's imports, only when this command runs
        from .study.run.pack import read_manifest  # noqa: PLC0415

        self.study = self.study or read_manifest(self.pack)["study"]
        check_folder_target(self.study, "study")


def cmd_unpack(args: list[str]) -> None:
    # as in cmd_pack: the pack's imports, only when this command runs
    from .study.run.pack import unpack  # noqa: PLC0415

    cfg = parse_config(UnpackConfig, args, "unpack")
    done = unpack(cfg.pack, cfg.study)
    print(
        f"unpacked into {cfg.study}: {done.written} file(s) written, {done.present} already there, {done.links} link(s)"
    )
    for rel in done.in_progress:
        print(f"  a training in progress goes on from its newest save: {rel}")
    print("go on with the study's command (it collects the left-out datasets again first)")


@dataclass
class SyncDocsConfig:
    """``factorworld sync-docs``: regenerate every committed study report (``docs/results/<study>/``) and rewrite
    the tables of ``docs/*.md`` fenced from them (``study/report/published.py``).

    Attributes:
        check: Change nothing; name what is stale and exit 1 if anything is.
        root: The repository checkout (default: this folder).
    """

    check: bool = False
    root: str = "."

    def __post_init__(self) -> None:
        if not (Path(self.root) / "docs").is_dir():
            raise ValueError(f"root {self.root} holds no docs/ folder: run sync-docs in the repository's checkout")


def cmd_sync_docs(args: list[str]) -> None:
    # every committed study's report (a report's stack, no LeRobot): only when this command runs
    from .study.report.published import RESULTS_ROOT, committed_studies, stale_published, sync_published  # noqa: PLC0415

    cfg = parse_config(SyncDocsConfig, ["--check=true" if arg == "--check" else arg for arg in args], "sync-docs")
    root = Path(cfg.root)
    if cfg.check:
        problems = stale_published(root)
        print("\n".join(problems) or "every committed report and fenced table is current")
        if problems:
            raise SystemExit(FAILURE_STATUS)
        return
    changed = sync_published(root)
    studies = ", ".join(committed_studies(root / RESULTS_ROOT)) or "none"
    print(f"regenerated the committed reports ({studies}); rewrote {len(changed)} docs file(s)")
    for path in changed:
        print(f"  {path}")


COMMANDS: dict[str, Callable[[list[str]], None]] = {
    "tasks": cmd_tasks,
    "factors": cmd_factors,
    "cameras": cmd_cameras,
    "sample": cmd_sample,
    "contact-sheet": cmd_contact_sheet,
    "collect": cmd_collect,
    "rt1-presets": cmd_rt1_presets,
    "study": cmd_study,
    "configs": cmd_configs,
    "profile": cmd_profile,
    "report": cmd_report,
    "compare-gaps": cmd_compare_gaps,
    "compare-curves": cmd_compare_curves,
    "compare-reruns": cmd_compare_reruns,
    "merge-results": cmd_merge_results,
    "pack": cmd_pack,
    "unpack": cmd_unpack,
    "sync-docs": cmd_sync_docs,
}


def main(argv: list[str] | None = None) -> None:
    """Run one command; a bad setting or a refusal prints one ``error: ...`` line and exits non-zero; anything
    else is a bug: one ``internal error:`` line naming the log file that holds its traceback."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return
    command, args = argv[0], argv[1:]
    try:
        if command not in COMMANDS:
            raise SettingError(f"unknown command {command!r}; valid commands: {', '.join(COMMANDS)}")
        COMMANDS[command](args)
    except SettingError as err:
        _fail(err, SETTING_ERROR_STATUS)
    except Exception as err:  # noqa: BLE001  (every exception is answered: a refusal in one line, a bug as one)
        if is_refusal(err):  # e.g. a refusal to touch a dataset collected with other settings
            _fail(err, FAILURE_STATUS)
        log = write_traceback(err, " ".join(argv))
        print(
            f"internal error: {type(err).__name__}: {one_line(str(err))} (a bug in lerobot_factorworld, not a "
            f"problem with your settings; the traceback is in {log}: please report it)",
            file=sys.stderr,
        )
        raise SystemExit(INTERNAL_ERROR_STATUS) from None


def _fail(err: BaseException, status: int) -> typing.NoReturn:
    print(f"error: {one_line(str(err))}", file=sys.stderr)
    raise SystemExit(status)


def run() -> None:
    """The ``factorworld`` program: :func:`main`, then the process ends without its last garbage collection,
    which would walk every object torch and LeRobot made at import (1.5-2.5 s at a study's exit; frozen
    objects are skipped). Not in :func:`main`, which tests call in a process that goes on."""
    try:
        main()
    finally:
        gc.freeze()


if __name__ == "__main__":
    run()
