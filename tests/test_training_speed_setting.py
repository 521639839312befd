"""The ``speed`` setting of bc and rt1 (``policies/common/speed.py``): ``default`` computes exactly what the policies
computed before the setting existed, ``fast`` (channels-last encoder input, bf16 autocast) stays close to it, a bad
value is refused in one line naming the valid ones, and the value travels with a saved policy."""

import json

import pytest
import torch
from lerobot.configs import FeatureType, PolicyFeature
from lerobot.configs.policies import PreTrainedConfig
from lerobot.optim.optimizers import load_optimizer_state, save_optimizer_state

import lerobot_factorworld.lerobot_plugin  # noqa: F401  (registers bc and rt1)
from lerobot_factorworld.policies.bc.configuration_bc import BCConfig
from lerobot_factorworld.policies.bc.modeling_bc import BCPolicy
from lerobot_factorworld.policies.common.language import LANGUAGE_EMBEDDING_KEY
from lerobot_factorworld.policies.common.speed import SPEEDS
from lerobot_factorworld.policies.rt1.configuration_rt1 import RT1Config
from lerobot_factorworld.policies.rt1.modeling_rt1 import RT1Policy

CAMERA = "observation.images.front"
STATE = "observation.state"
ACTION = {"action": PolicyFeature(FeatureType.ACTION, (4,))}

# What the code before the setting (commit 65b4b2b) computed for these seeds and inputs, on this project's CPU.
# Float32 kernels may differ in the last bits on another CPU: hence a tolerance far below any real change.
BC_ACTIONS_BEFORE = [
    [-0.028465555980801582, -0.08140075951814651, -0.048075221478939056, 0.18591201305389404],
    [0.018984884023666382, -0.07092459499835968, -0.059712473303079605, 0.1985536515712738],
    [0.050723396241664886, -0.15764391422271729, -0.08332303911447525, 0.1489821970462799],
]
BC_LOSS_BEFORE = 0.39171943068504333
# rt1 from commit 65b4b2b (before the setting existed), a fresh model: one forward in training mode (seed 1 for the
# augmentations and dropout) and one in eval mode; the same at one and two threads. (After optimizer steps Adam
# amplifies the thread count's last-bit differences into 1e-3 of a logit, so no step is taken here.)
RT1_TRAIN_LOSS_BEFORE = [5.942093372344971, 5.928598880767822]
RT1_PER_SAMPLE_LOSS_BEFORE = [5.87602424621582, 5.786473751068115]
RT1_LOGITS_BEFORE = [  # logits[:, -1, :, :3] in eval mode
    [
        [0.12275031954050064, -0.24032562971115112, -0.8446997404098511],
        [0.1064697727560997, 0.049218617379665375, -0.4801682233810425],
        [0.0796784833073616, -0.09040085226297379, -1.060877799987793],
        [0.17558717727661133, -0.06810306757688522, -0.9032981395721436],
    ],
    [
        [0.1227564886212349, -0.24032434821128845, -0.8447015285491943],
        [0.10647831112146378, 0.04921659082174301, -0.4801688492298126],
        [0.07968774437904358, -0.09040147811174393, -1.0608819723129272],
        [0.1755962073802948, -0.06810364872217178, -0.9033011198043823],
    ],
]
BEFORE = {"rtol": 1e-5, "atol": 1e-6}
BF16 = {"rtol": 2e-2, "atol": 2e-2}  # bf16 keeps 8 significant bits: about 0.4% per rounding


def make_bc(**overrides) -> BCPolicy:
    torch.manual_seed(0)
    features = {CAMERA: PolicyFeature(FeatureType.VISUAL, (3, 84, 84)), STATE: PolicyFeature(FeatureType.STATE, (8,))}
    return BCPolicy(BCConfig(device="cpu", input_features=features, output_features=dict(ACTION), **overrides))


def make_rt1(**overrides) -> RT1Policy:
    torch.manual_seed(0)
    features = {CAMERA: PolicyFeature(FeatureType.VISUAL, (3, 84, 84))}
    return RT1Policy(RT1Config(device="cpu", input_features=features, output_features=dict(ACTION), **overrides))


def bc_batch() -> dict:
    g = torch.Generator().manual_seed(0)
    return {
        CAMERA: torch.rand(3, 3, 84, 84, generator=g),
        STATE: torch.randn(3, 8, generator=g),
        "action": torch.rand(3, 4, generator=g) * 2 - 1,
    }


def rt1_batch(n: int = 2) -> dict:
    g = torch.Generator().manual_seed(0)
    return {
        CAMERA: torch.rand(n, 6, 3, 84, 84, generator=g),
        LANGUAGE_EMBEDDING_KEY: torch.randn(n, 384, generator=g),
        "action": torch.rand(n, 6, 4, generator=g) * 2 - 1,
    }


def test_default_is_the_setting_and_computes_what_bc_computed_before():
    policy = make_bc()
    assert policy.config.speed == "default" and SPEEDS == ("default", "fast")
    batch = bc_batch()
    policy.train()  # no augmentation by default: the loss is deterministic
    loss, _ = policy.forward(batch)
    torch.testing.assert_close(loss, torch.tensor(BC_LOSS_BEFORE), **BEFORE)
    actions = policy.select_action(batch)
    torch.testing.assert_close(actions, torch.tensor(BC_ACTIONS_BEFORE), **BEFORE)


def test_default_is_the_setting_and_computes_what_rt1_computed_before():
    policy = make_rt1()
    assert policy.config.speed == "default"
    batch = rt1_batch()
    policy.eval()  # first: a training forward updates the batch norms' running statistics
    with torch.no_grad():
        per_sample, _ = policy.forward(batch, reduction="none")
        logits = policy.model({CAMERA: batch[CAMERA]}, batch[LANGUAGE_EMBEDDING_KEY])
    policy.train()
    torch.manual_seed(1)  # the augmentations' and dropout's draws
    train_loss, _ = policy.forward(batch, reduction="none")
    torch.testing.assert_close(train_loss.detach(), torch.tensor(RT1_TRAIN_LOSS_BEFORE), **BEFORE)
    torch.testing.assert_close(per_sample, torch.tensor(RT1_PER_SAMPLE_LOSS_BEFORE), **BEFORE)
    torch.testing.assert_close(logits[:, -1, :, :3], torch.tensor(RT1_LOGITS_BEFORE), **BEFORE)


def first_conv_inputs(policy, conv: torch.nn.Module, batch: dict, train: bool) -> dict:
    """What ``conv`` received during one forward (train) or one action selection: dtype, layout, autocast."""
    seen = {}

    def hook(module, inputs, output):
        (x,) = inputs
        seen.update(
            channels_last=x.is_contiguous(memory_format=torch.channels_last) and not x.is_contiguous(),
            autocast=torch.is_autocast_enabled("cpu"),
            output=output.dtype,
        )

    handle = conv.register_forward_hook(hook)
    try:
        if train:
            policy.train()
            loss, _ = policy.forward(batch)
            assert loss.dtype == torch.float32
        else:
            assert policy.select_action(batch).dtype == torch.float32
    finally:
        handle.remove()
    return seen


@pytest.mark.parametrize("train", [True, False], ids=["forward", "select_action"])
def test_what_each_setting_runs(train):
    """default: float32, bc's images in their usual layout (rt1's stem: channels-last, as always); fast: bf16
    autocast, channels-last images, rt1's depthwise convolutions in float32. The weights keep their layout."""
    window = rt1_batch(1)
    frame = {CAMERA: window[CAMERA][:, -1], LANGUAGE_EMBEDDING_KEY: window[LANGUAGE_EMBEDDING_KEY]}
    for speed, bf16 in (("default", False), ("fast", True)):
        bc = make_bc(speed=speed)
        seen = first_conv_inputs(bc, bc.model.encoder.convs[0], bc_batch(), train)
        assert seen == {"channels_last": bf16, "autocast": bf16, "output": torch.bfloat16 if bf16 else torch.float32}
        rt1 = make_rt1(speed=speed)
        batch = window if train else frame
        seen = first_conv_inputs(rt1, rt1.model.encoder.net._conv_stem, batch, train)
        assert seen == {"channels_last": True, "autocast": bf16, "output": torch.bfloat16 if bf16 else torch.float32}
        rt1.reset()
        depthwise = rt1.model.encoder.net._blocks[1]._depthwise_conv
        assert first_conv_inputs(rt1, depthwise, batch, train)["output"] == torch.float32
        for policy in (bc, rt1):
            assert all(p.is_contiguous() and p.dtype == torch.float32 for p in policy.parameters())


def test_fast_bc_is_close_to_default():
    default, fast = make_bc(), make_bc(speed="fast")
    assert all(torch.equal(a, b) for a, b in zip(default.parameters(), fast.parameters(), strict=True))
    batch = bc_batch()
    losses = []
    for policy in (default, fast):
        policy.train()
        loss, _ = policy.forward(batch)
        loss.backward()
        losses.append(loss)
    torch.testing.assert_close(losses[1], losses[0], **BF16)
    for a, b in zip(default.parameters(), fast.parameters(), strict=True):
        assert b.grad.dtype == torch.float32
        cosine = torch.nn.functional.cosine_similarity(a.grad.flatten(), b.grad.flatten(), dim=0)
        assert cosine > 0.98, cosine  # the same update direction
    torch.testing.assert_close(fast.select_action(batch), default.select_action(batch), **BF16)


def test_fast_rt1_is_close_to_default_and_selects_float32_actions():
    default, fast = make_rt1(), make_rt1(speed="fast")
    batch = rt1_batch()
    for policy in (default, fast):
        policy.eval()
    with torch.no_grad():
        per_default, _ = default.forward(batch, reduction="none")
        per_fast, _ = fast.forward(batch, reduction="none")
    assert per_fast.dtype == torch.float32
    torch.testing.assert_close(per_fast, per_default, **BF16)
    # with and without token reuse (bf16 tokens kept across steps): float32 actions within the bins' range
    for reuse in (True, False):
        fast.config.token_reuse = reuse
        fast.reset()
        for t in range(3):
            action = fast.select_action(
                {CAMERA: batch[CAMERA][:, t], LANGUAGE_EMBEDDING_KEY: batch[LANGUAGE_EMBEDDING_KEY]}
            )
            assert action.shape == (2, 4) and action.dtype == torch.float32 and action.abs().max() <= 1


@pytest.mark.parametrize("config_class", [BCConfig, RT1Config], ids=["bc", "rt1"])
def test_a_bad_speed_is_refused_in_one_line_naming_the_valid_values(config_class):
    with pytest.raises(ValueError) as err:
        config_class(device="cpu", speed="turbo")
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith("unknown speed 'turbo'; valid: default, fast ")


@pytest.mark.parametrize("make", [make_bc, make_rt1], ids=["bc", "rt1"])
def test_speed_round_trips_through_the_saved_policy(make, tmp_path):
    policy = make(speed="fast")
    policy.save_pretrained(tmp_path / "fast")
    assert json.loads((tmp_path / "fast" / "config.json").read_text())["speed"] == "fast"
    assert PreTrainedConfig.from_pretrained(tmp_path / "fast").speed == "fast"
    loaded = type(policy).from_pretrained(tmp_path / "fast")
    assert loaded.config.speed == "fast"
    assert all(torch.equal(a, b) for a, b in zip(policy.state_dict().values(), loaded.state_dict().values()))

    # a checkpoint saved before the setting existed (no "speed" in its config.json) loads as default
    make().save_pretrained(tmp_path / "old")
    config = json.loads((tmp_path / "old" / "config.json").read_text())
    assert config.pop("speed") == "default"
    (tmp_path / "old" / "config.json").write_text(json.dumps(config))
    assert type(policy).from_pretrained(tmp_path / "old").config.speed == "default"


@pytest.mark.parametrize("make", [make_bc, make_rt1], ids=["bc", "rt1"])
def test_fast_training_state_saves_as_lerobot_train_saves_it(make, tmp_path):
    """The weights keep their layout under fast, so LeRobot's optimizer checkpoint (safetensors, contiguous tensors
    only) saves Adam's moments and loads them back."""
    policy = make(speed="fast")
    batch = bc_batch() if isinstance(policy, BCPolicy) else rt1_batch(1)
    optimizer = torch.optim.Adam(policy.parameters(), lr=1e-3)
    policy.train()
    loss, _ = policy.forward(batch)
    loss.backward()
    optimizer.step()
    save_optimizer_state(optimizer, tmp_path)
    restored = load_optimizer_state(torch.optim.Adam(policy.parameters(), lr=1e-3), tmp_path)
    state, back = optimizer.state_dict()["state"], restored.state_dict()["state"]
    assert state.keys() == back.keys() and all(torch.equal(state[k]["exp_avg"], back[k]["exp_avg"]) for k in state)


def test_the_fast_setting_enters_the_training_key_and_the_default_keeps_every_key():
    from lerobot_factorworld.study.plan.config import StudyConfig
    from lerobot_factorworld.study.plan.grid import make_plan

    def train_keys(policy: dict) -> list[str]:
        cfg = StudyConfig(tasks=["door-open"], factors=["light"], train_factors=["light"],
                          methods=[{"name": "bc", "policy": policy}])  # fmt: skip
        return [s.key for s in make_plan(cfg).of_kind("train")]

    plain, fast = train_keys({"type": "bc"}), train_keys({"type": "bc", "speed": "fast"})
    assert plain != fast
    assert plain == train_keys({"type": "bc"})  # unchanged by the setting's existence
