"""The ``factorworld`` env config an evaluation runs in: a trained checkpoint's ``train`` condition is its
dataset's own environments (read from the dataset, as ``lerobot-eval --env.dataset_root`` reads them); a given
checkpoint's is sampled from the same settings (``EnvInputs``), observed as it was made to observe."""

from __future__ import annotations

from ...envs.lerobot_obs import LEROBOT_METAWORLD_OBS
from ...protocol.conditions import TRAIN_SUITE
from .inputs import CollectInputs, EnvInputs, EvalInputs


def env_config(
    env: EnvInputs,
    data_root: str | None = None,
    condition: str = TRAIN_SUITE,
    n_test_envs: int | None = None,
    episode_length: int | None = None,
):
    """The env config of ``condition`` (alone) in ``env``'s environments; with ``data_root`` the ``train``
    environments are that dataset's (its side-car holds the settings ``env`` repeats)."""
    # Deliberately here: the env config subclasses LeRobot's (about 4 s to import); planning never needs it.
    from ...adapters.env_config import FactorWorldEnvConfig  # noqa: PLC0415

    is_train = condition == TRAIN_SUITE
    shifted = {} if is_train else {"n_test_envs": n_test_envs}
    # LeRobot's observation fixes its camera and image size (the config refuses them)
    view = {} if env.obs == LEROBOT_METAWORLD_OBS else {"cameras": env.cameras, "image_size": env.image_size}
    if env.obs != LEROBOT_METAWORLD_OBS:  # LeRobot's view renders at Meta-World's own quality (the env's default)
        view["quality"] = env.render_quality
    if data_root is not None:
        train = {"dataset_root": data_root}
    else:
        train = {
            "n_train_envs": env.n_envs,
            "train_factors": list(env.train_factors),
            "seed": env.seed,
            "sampling": env.sampling_options(),
        }
    return FactorWorldEnvConfig(
        task=env.task,
        obs=env.obs,
        episode_length=episode_length,
        shifts=[] if is_train else [condition],
        include_train=is_train,
        **view,
        **train,
        **shifted,
    )


def eval_env_config(env: CollectInputs | EnvInputs, data_root: str | None, inputs: EvalInputs):
    """The env config of one evaluation step's condition: a collection's environments from its dataset at
    ``data_root``, or a given checkpoint's (``data_root`` None)."""
    if isinstance(env, CollectInputs):
        env = env.environments()
    return env_config(env, data_root, inputs.condition, inputs.n_test_envs, inputs.max_episode_steps)
