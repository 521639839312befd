"""bc's photometric distortion (issue 18, item 4): colour jitter, random cutout and Gaussian pixel noise,
checked on a fixed image; ``none`` and ``shift`` apply neither cutout nor noise."""

import pytest
import torch
from lerobot.configs import FeatureType, PolicyFeature

import lerobot_factorworld.lerobot_plugin  # noqa: F401  (registers bc)
from lerobot_factorworld.policies.bc.augment import ImageAugmentation
from lerobot_factorworld.policies.bc.configuration_bc import BCConfig
from lerobot_factorworld.policies.bc.modeling_bc import BCPolicy
from lerobot_factorworld.policies.common.augment import cutout_sides, gaussian_noise, random_cutout

GREY = 0.5  # the fixed image: uniform grey, so any cutout or noise shows, and a shift changes nothing


def grey(n: int, side: int = 84) -> torch.Tensor:
    return torch.full((n, 3, side, side), GREY)


def black_box(image: torch.Tensor) -> tuple[int, int] | None:
    """(height, width) of the black rectangle in a (3, H, W) image, or None; asserts it is one filled rectangle."""
    black = (image == 0).all(dim=0)
    if not black.any():
        return None
    rows = black.any(dim=1).nonzero().flatten()
    cols = black.any(dim=0).nonzero().flatten()
    h, w = int(rows[-1] - rows[0] + 1), int(cols[-1] - cols[0] + 1)
    assert int(black.sum()) == h * w, "the cutout is not one filled rectangle"
    return h, w


def test_cutout_is_one_black_rectangle_of_10_to_29_px_at_84_px_per_image():
    assert cutout_sides(84, (0.12, 0.35)) == (10, 29)  # RAD's 10-29 px
    assert cutout_sides(8, (0.01, 2.0)) == (1, 8)  # at least 1 px, at most the side
    torch.manual_seed(0)
    out = random_cutout(grey(300), (0.12, 0.35))
    sides = [black_box(img) for img in out]
    assert all(s is not None and 10 <= s[0] <= 29 and 10 <= s[1] <= 29 for s in sides)
    assert {s[0] for s in sides} >= {10, 29} and len(set(sides)) > 100  # drawn per image, over the whole range
    outside = out != 0
    assert (out[outside] == GREY).all()  # nothing else changes
    covered = (out == 0).all(dim=1).any(dim=0)  # (H, W): pixels some box covered
    assert covered.any(dim=1).all() and covered.any(dim=0).all()  # positions drawn per image, edges reached


def test_gaussian_noise_has_the_stated_standard_deviation_and_stays_in_range():
    torch.manual_seed(0)
    x = grey(64, 32)
    noise = gaussian_noise(x, 0.1) - x
    assert abs(noise.mean().item()) < 0.005 and noise.std().item() == pytest.approx(0.1, rel=0.03)
    clipped = gaussian_noise(torch.ones(4, 3, 8, 8), 0.5)
    assert clipped.max() <= 1 and clipped.min() >= 0 and (clipped < 1).any()


def test_color_applies_cutout_and_noise_on_a_fixed_image():
    # jitter off (factor 0), every image distorted: cutout only, then noise only, then both
    x = grey(40)
    torch.manual_seed(0)
    cut = ImageAugmentation("color", jitter=0.0, prob=1.0, cutout_prob=1.0, noise_prob=0.0).train()(x)
    assert all(black_box(img) is not None for img in cut) and ((cut == 0) | (cut == GREY)).all()
    torch.manual_seed(0)
    noisy = ImageAugmentation("color", jitter=0.0, prob=1.0, cutout_prob=0.0, noise_prob=1.0).train()(x)
    assert all((img != GREY).float().mean() > 0.9 for img in noisy)
    assert (noisy - x).std().item() == pytest.approx(0.1, rel=0.05)
    torch.manual_seed(0)
    both = ImageAugmentation("shift+color", jitter=0.0, prob=1.0, cutout_prob=1.0, noise_prob=1.0).train()(x)
    dark = both.mean(dim=1) < 0.15  # (N, H, W): the box under the noise (grey + noise is never this dark)
    assert all(dark[i].sum() >= 100 for i in range(len(x)))  # a box of >= 10 x 10 px in every image
    assert ((both != GREY).flatten(1).float().mean(dim=1) > 0.9).all()  # and noise everywhere


def test_default_color_shares_of_cutout_and_noise_per_image():
    """Defaults: distortion on 30% of images; among those, cutout and noise each with probability 0.5."""
    torch.manual_seed(0)
    x = grey(4000, 24)
    aug = ImageAugmentation("color").train()
    assert (aug.prob, aug.cutout_prob, aug.cutout_size, aug.noise_prob, aug.noise_std) == (
        0.3,
        0.5,
        (0.12, 0.35),
        0.5,
        0.1,
    )
    out = aug(x)
    changed = (out != x).flatten(1).any(dim=1)
    cut = (out.mean(dim=1) < 0.15).flatten(1).sum(dim=1) >= 9  # a dark box of >= 3x3 px (24 px: sides 3-8)
    noisy = (out.flatten(1) != out.flatten(1)[:, :1]).float().mean(dim=1) > 0.5  # most pixels differ
    assert 0.26 < changed.float().mean() < 0.34
    assert not (cut & ~changed).any() and not (noisy & ~changed).any()  # only distorted images
    assert 0.12 < cut.float().mean() < 0.18 and 0.12 < noisy.float().mean() < 0.18  # 0.3 x 0.5 = 0.15
    assert out.min() >= 0 and out.max() <= 1


@pytest.mark.parametrize("mode", ["none", "shift"])
def test_none_and_shift_apply_neither_cutout_nor_noise(mode):
    x = grey(64)  # uniform: a shift (edges replicated) leaves it as it is
    torch.manual_seed(0)
    aug = ImageAugmentation(mode, prob=1.0, cutout_prob=1.0, noise_prob=1.0).train()
    assert torch.equal(aug(x), x)


def test_seeded_runs_augment_identically_and_eval_mode_not_at_all():
    x = torch.rand(16, 3, 84, 84, generator=torch.Generator().manual_seed(1))
    aug = ImageAugmentation("shift+color", prob=1.0).train()
    torch.manual_seed(5)
    a = aug(x)
    torch.manual_seed(5)
    assert torch.equal(aug(x), a) and not torch.equal(a, x)
    assert torch.equal(aug.eval()(x), x)


def test_the_policy_passes_its_settings_and_refuses_bad_ones():
    features = {
        "observation.images.front": PolicyFeature(FeatureType.VISUAL, (3, 84, 84)),
        "observation.state": PolicyFeature(FeatureType.STATE, (8,)),
    }
    action = {"action": PolicyFeature(FeatureType.ACTION, (4,))}

    def cfg(**kw):
        return BCConfig(device="cpu", input_features=dict(features), output_features=dict(action), **kw)

    aug = BCPolicy(cfg(augmentation="color", cutout_prob=0.2, cutout_size=[0.1, 0.2], noise_std=0.05)).model.augment
    assert (aug.cutout_prob, aug.cutout_size, aug.noise_prob, aug.noise_std) == (0.2, (0.1, 0.2), 0.5, 0.05)
    for bad in ({"cutout_prob": 1.5}, {"noise_prob": -0.1}, {"noise_std": -1.0}, {"cutout_size": (0.4, 0.2)}):
        with pytest.raises(ValueError):
            cfg(**bad)


def test_without_cutout_and_noise_color_is_the_earlier_jitter_only_stream():
    """``cutout_prob=0, noise_prob=0``: the same images and the same RNG stream as ``color`` before issue 18."""

    def earlier(images: torch.Tensor) -> torch.Tensor:  # the jitter-only forward, as it was
        chosen = (torch.rand(images.shape[0]) < 0.3).nonzero().flatten().tolist()
        images = images.clone()
        for i in chosen:
            images[i] = jitter(images[i])
        return images

    aug = ImageAugmentation("color", cutout_prob=0.0, noise_prob=0.0).train()
    jitter = aug.jitter
    x = torch.rand(32, 3, 16, 16, generator=torch.Generator().manual_seed(2))
    torch.manual_seed(3)
    new = [aug(x), aug(x)]
    torch.manual_seed(3)
    assert all(torch.equal(a, earlier(x)) for a in new)
