"""bc's processors: LeRobot's defaults (rename, batch, device, normalise / unnormalise).

With ``use_language`` the instruction is embedded by the registered MiniLM step shared with RT-1
(``common/language.py``, offline weights from a package), so saved checkpoints rebuild it.
"""

from __future__ import annotations

import torch
from lerobot.processor import make_default_policy_processor_steps, make_policy_processor_pipelines

from ..common.language import LanguageEmbeddingStep
from .configuration_bc import BCConfig


def make_bc_pre_post_processors(config: BCConfig, dataset_stats: dict[str, dict[str, torch.Tensor]] | None = None):
    steps = make_default_policy_processor_steps(config, dataset_stats)
    language = [LanguageEmbeddingStep()] if config.use_language else []
    return make_policy_processor_pipelines(
        input_steps=[steps.rename_observations, steps.add_batch_dim, *language, steps.to_device, steps.normalize],
        output_steps=[steps.unnormalize, steps.to_cpu],
    )
