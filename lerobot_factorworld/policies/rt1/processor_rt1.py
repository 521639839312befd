"""RT-1's processors: LeRobot's defaults plus the registered MiniLM instruction-embedding step
(``common/language.py``), so saved checkpoints rebuild it from ``policy_preprocessor.json``."""

from __future__ import annotations

import torch
from lerobot.processor import make_default_policy_processor_steps, make_policy_processor_pipelines

from ..common.language import LanguageEmbeddingStep
from .configuration_rt1 import RT1Config


def make_rt1_pre_post_processors(config: RT1Config, dataset_stats: dict[str, dict[str, torch.Tensor]] | None = None):
    steps = make_default_policy_processor_steps(config, dataset_stats)
    return make_policy_processor_pipelines(
        input_steps=[
            steps.rename_observations,
            steps.add_batch_dim,
            LanguageEmbeddingStep(language_dim=config.language_dim),
            steps.to_device,
            steps.normalize,
        ],
        output_steps=[steps.unnormalize, steps.to_cpu],
    )
