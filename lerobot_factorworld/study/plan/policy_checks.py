"""What LeRobot says of a method's policy settings: checked last, since importing LeRobot's policy configs takes
seconds and only a study's validation needs them, not every importer of the study's settings."""

from __future__ import annotations

import logging

import draccus

from .method_config import MethodConfig
from .train_settings import TrainSettings


def check_policy(method: MethodConfig) -> None:
    """The method's policy type exists and accepts its overrides (as ``lerobot-train`` will parse them)."""
    import lerobot.policies  # noqa: F401, PLC0415 - registers LeRobot's own policy types (act, diffusion, ...): seconds
    from lerobot.configs.policies import PreTrainedConfig  # noqa: PLC0415 - LeRobot, as above

    from ...policies.bc import configuration_bc  # noqa: F401, PLC0415 - registers bc
    from ...policies.rt1 import configuration_rt1  # noqa: F401, PLC0415 - registers rt1

    kind = method.policy["type"]
    if kind not in PreTrainedConfig.get_known_choices():
        known = ", ".join(sorted(PreTrainedConfig.get_known_choices()))
        raise ValueError(f"method {method.name!r}: unknown policy type {kind!r}; valid types: {known}")
    overrides = {k: v for k, v in method.policy.items() if k != "type"}
    # On the CPU: without a device LeRobot's config asks torch.cuda.is_available(), and a process that has asked
    # can no longer fork workers that use CUDA ("Cannot re-initialize CUDA in forked subprocess"). Where the
    # study trains and evaluates is train.device and eval.device, checked where the steps run.
    overrides_cpu = {**overrides, "device": "cpu"}
    quiet = logging.getLogger()
    level, quiet.level = quiet.level, logging.ERROR  # constructing a config logs device warnings
    try:
        draccus.decode(PreTrainedConfig.get_choice_class(kind), overrides_cpu)
    except Exception as err:  # draccus reports unknown fields and bad values; the innermost cause says why
        while err.__cause__ is not None:
            err = err.__cause__
        raise ValueError(f"method {method.name!r}: bad policy settings {overrides}: {err}") from None
    finally:
        quiet.level = level


def check_extendable(method: MethodConfig, train: TrainSettings) -> None:
    """A training that ``extends`` shorter ones continues them exactly only when its learning rate does not depend on
    the budget: refused for a policy whose training preset has a schedule (LeRobot builds it from ``--steps``)."""
    import lerobot.policies  # noqa: F401, PLC0415 - LeRobot's policy types (seconds), as check_policy imports them
    from lerobot.configs.policies import PreTrainedConfig  # noqa: PLC0415

    overrides = {k: v for k, v in method.policy.items() if k != "type"}
    config = draccus.decode(PreTrainedConfig.get_choice_class(method.policy["type"]), {**overrides, "device": "cpu"})
    scheduler = config.get_scheduler_preset()
    if train.extends and scheduler is not None:
        raise ValueError(
            f"method {method.name!r}: train.extends needs a learning rate that does not depend on the budget, but "
            f"policy type {method.policy['type']!r} trains with a {type(scheduler).__name__} schedule built from "
            "--steps: train it in one run (drop extends)"
        )
