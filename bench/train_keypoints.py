"""Train the dial keypoint network (pivot, needle tip, scale min and max end marks).

    pip install -e .[train]          # torch (CPU) and onnx: only needed here
    python bench/train_keypoints.py [--n-clean 800 --n-field 800 --n-hard 500]
        [--minutes 25] [--seed 11] [--cache A.npz,B.npz] [--gen-only]
        [--out app/core/meter/models/dial_keypoints.onnx]

The data come from the project's own styled gauge generator (``sim_robot.gauge_scene``),
from the TUNING families only (plant, dark, colour, process) at the clean, field and hard
levels; the held-out family (heritage) is never drawn here.  Each rendered image is cut
to a square around the ground-truth dial (1.6 x its outer diameter, 224 px) and kept with
its four keypoints; training then draws random crops from these (side 0.92-1.35 x the dial's
diameter, shifted by up to 8 %, rotated by up to 25 deg, brightness, contrast, blur and
noise jitter) so the network copes with an imperfect crop from the classical dial finder.
A gauge whose scale runs counter-clockwise is mirrored left-right (the reader does the same
with the profile's direction), so the network only ever sees clockwise scales.

The network (:class:`KeypointNet`, about 0.3 M parameters) is a small U-Net: 128 x 128 BGR
in, four 32 x 32 heatmap logits out (stride 4).  The loss is the cross-entropy between each
channel's spatial softmax and a Gaussian target (sigma 0.8 cell), so the output is a spatial
probability whose spread says how sure the network is.  It is exported to ONNX (opset 13,
read by OpenCV's dnn module) for :mod:`app.core.meter.keypoints`.

The committed weights (``app/core/meter/models/dial_keypoints.onnx``, 1.2 MB) were made
on the project's shared 2-core CPU (load average about 6, other jobs running) by::

    python bench/train_keypoints.py --gen-only --seed 11 --n-clean 800 --n-field 800 \
        --n-hard 500 --cache /tmp/lkp/data11.npz      # and the same with --seed 12 (data12)
    python bench/train_keypoints.py --seed 11 --minutes 24 \
        --cache /tmp/lkp/data11.npz,/tmp/lkp/data12.npz

Measured: the two generation runs side by side took 7.8 min of wall time (4200 samples);
training took 24.0 min of wall time (2749 steps of 16 crops, the ``--minutes`` cap, two
torch threads) to a loss of 2.49 (its floor, the targets' own entropy, is 2.39).  So the
weights reproduce on a 2-core CPU in about 35 minutes, well within an hour; on an idle
machine the same step budget is reached sooner.  Everything is seeded (numpy, torch), but
the training stops on wall time and torch's CPU kernels may differ in the last bits between
machines, so a rerun gives weights of the same quality, not identical bytes.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from sim_robot.gauge_scene import distort_point, render_sample  # noqa: E402
from sim_robot.gauge_styles import HELD_OUT_FAMILY, TUNING_FAMILIES, random_style  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
STORE = 224  # stored square around the dial
STORE_FILL = 1.6  # stored side / the dial's outer diameter
IN = 128  # network input
OUT = 32  # heatmap side (stride 4)
K = 4  # pivot, tip, min end mark, max end mark


# ----------------------------------------------------------------------------- data


def _dial_circle(truth: dict, size_guess: float | None):
    """The dial's outer circle (centre, radius) in image pixels, and the dial crop size."""
    hm = np.array(truth["homography"], float)
    k = truth["lens_k"]
    w, h = truth["frame_size"]
    if size_guess is None:
        # undistort the pivot, then solve H (c, c) = p for the crop centre c
        px, py = truth["pivot_xy"]
        cx, cy, s = w / 2.0, h / 2.0, math.hypot(w, h) / 2.0
        dx, dy = (px - cx) / s, (py - cy) / s
        f = 1 + k * (dx * dx + dy * dy)
        ux, uy = cx + dx * f * s, cy + dy * f * s
        a, b = hm[0, 0] + hm[0, 1], hm[0, 2]
        e, g = hm[2, 0] + hm[2, 1], hm[2, 2]
        c1 = (b - ux * g) / (ux * e - a)
        a2, b2 = hm[1, 0] + hm[1, 1], hm[1, 2]
        c2 = (b2 - uy * g) / (uy * e - a2)
        size_guess = c1 + c2  # 2 c
    c = size_guess / 2.0
    t = np.linspace(0, 2 * np.pi, 32, endpoint=False)
    pts = []
    for q in t:
        x, y = c + 0.49 * size_guess * math.cos(q), c + 0.49 * size_guess * math.sin(q)
        v = hm @ np.array([x, y, 1.0])
        pts.append(distort_point(v[0] / v[2], v[1] / v[2], k, w, h))
    pts = np.array(pts)
    centre = pts.mean(0)
    return centre, float(np.hypot(*(pts - centre).T).mean()), size_guess


def _tip(truth: dict, style, size: float):
    hm = np.array(truth["homography"], float)
    a = math.radians(truth["needle_angle_deg"])
    L = style.needle_len * size
    x, y = size / 2 + L * math.sin(a), size / 2 - L * math.cos(a)
    v = hm @ np.array([x, y, 1.0])
    w, h = truth["frame_size"]
    return distort_point(v[0] / v[2], v[1] / v[2], truth["lens_k"], w, h)


def make_sample(family: str, level: str, rng: np.random.Generator):
    """One stored sample: (224 x 224 BGR crop, 4 x 2 keypoints in it, clockwise flag)."""
    assert family != HELD_OUT_FAMILY, "the held-out family is never used for training"
    style = random_style(family, rng)
    img, truth = render_sample(family, level, rng, style=style)
    centre, radius, size = _dial_circle(truth, 300.0 if level == "clean" else None)
    kps = np.array([truth["pivot_xy"], _tip(truth, style, size), truth["min_mark_xy"],
                    truth["max_mark_xy"]], float)
    side = STORE_FILL * 2 * radius
    s = STORE / side
    m = np.array([[s, 0, STORE / 2 - s * centre[0]], [0, s, STORE / 2 - s * centre[1]]])
    crop = cv2.warpAffine(img, m, (STORE, STORE), flags=cv2.INTER_AREA,
                          borderMode=cv2.BORDER_REPLICATE)
    kp = kps @ m[:, :2].T + m[:, 2]
    return crop, kp.astype(np.float32), style.max_angle_deg > style.min_angle_deg


def generate(counts: dict[str, int], seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    imgs, kps, cw = [], [], []
    t0 = time.perf_counter()
    for level, n in counts.items():
        for i in range(n):
            c, k, d = make_sample(TUNING_FAMILIES[i % len(TUNING_FAMILIES)], level, rng)
            imgs.append(c)
            kps.append(k)
            cw.append(d)
        print(f"  generated {n} {level} samples [{time.perf_counter() - t0:.0f} s]", flush=True)
    return {"img": np.stack(imgs), "kp": np.stack(kps), "cw": np.array(cw)}


def augment(img: np.ndarray, kp: np.ndarray, cw: bool, rng: np.random.Generator):
    """A random 128 x 128 crop of a stored sample (the dial finder's imperfect crop)."""
    diam = STORE / STORE_FILL
    side = diam * rng.uniform(0.92, 1.35)
    shift = rng.uniform(-0.08, 0.08, 2) * side
    rot = math.radians(rng.uniform(-25, 25))
    s = IN / side
    ca, sa = math.cos(rot) * s, math.sin(rot) * s
    cx, cy = STORE / 2 + shift[0], STORE / 2 + shift[1]
    m = np.array([[ca, sa, IN / 2 - ca * cx - sa * cy], [-sa, ca, IN / 2 + sa * cx - ca * cy]])
    if not cw:  # canonical clockwise scale: mirror left-right
        m = np.array([[-1, 0, IN - 1.0], [0, 1, 0]]) @ np.vstack([m, [0, 0, 1]])
    out = cv2.warpAffine(img, m, (IN, IN), flags=cv2.INTER_AREA, borderMode=cv2.BORDER_REPLICATE)
    k = kp @ m[:, :2].T + m[:, 2]
    out = out.astype(np.float32)
    out = out * rng.uniform(0.7, 1.3) + rng.uniform(-30, 30)
    if rng.random() < 0.3:
        out = cv2.GaussianBlur(out, (0, 0), rng.uniform(0.3, 1.2))
    if rng.random() < 0.5:
        out += rng.normal(0, rng.uniform(1, 6), out.shape).astype(np.float32)
    if rng.random() < 0.2:  # colour cast
        out *= rng.uniform(0.85, 1.15, 3).astype(np.float32)
    return np.clip(out, 0, 255), k


def targets(kp: np.ndarray, sigma: float = 0.8) -> np.ndarray:
    """Gaussian target distributions on the 32 x 32 grid (each sums to 1)."""
    g = (np.arange(OUT) + 0.5)
    t = np.zeros((K, OUT, OUT), np.float32)
    for j in range(K):
        x, y = kp[j] * OUT / IN
        e = np.exp(-0.5 * ((g[None, :] - x) ** 2 + (g[:, None] - y) ** 2) / sigma ** 2)
        if e.sum() < 1e-6:  # off the grid: nearest cell
            e[int(np.clip(y, 0, OUT - 1)), int(np.clip(x, 0, OUT - 1))] = 1.0
        t[j] = e / e.sum()
    return t


# ----------------------------------------------------------------------------- network


def build_model():
    import torch
    from torch import nn

    def cbr(i, o, s=1, d=1):
        return nn.Sequential(nn.Conv2d(i, o, 3, s, d, dilation=d, bias=False),
                             nn.BatchNorm2d(o), nn.ReLU(inplace=True))

    def cbr1(i, o):
        return nn.Sequential(nn.Conv2d(i, o, 1, bias=False), nn.BatchNorm2d(o), nn.ReLU(True))

    class KeypointNet(nn.Module):
        """Small U-Net: 128 -> 64 -> 32 -> 16 -> 8, decoded back to 32 (stride 4)."""

        def __init__(self):
            super().__init__()
            self.e1 = cbr(3, 16, 2)  # 64
            self.e2 = nn.Sequential(cbr(16, 24, 2), cbr(24, 24))  # 32
            self.e3 = nn.Sequential(cbr(24, 48, 2), cbr(48, 48))  # 16
            self.e4 = nn.Sequential(cbr(48, 96, 2), cbr(96, 96), cbr(96, 96, d=2))  # 8
            self.d3 = nn.Sequential(cbr1(96 + 48, 48), cbr(48, 48))
            self.d2 = nn.Sequential(cbr1(48 + 24, 32), cbr(32, 32))
            self.head = nn.Conv2d(32, K, 1)

        def forward(self, x):
            x = x / 127.5 - 1.0
            b = self.e2(self.e1(x))
            c = self.e3(b)
            d = self.e4(c)
            up = nn.functional.interpolate
            y = self.d3(torch.cat([up(d, scale_factor=2.0, mode="nearest"), c], 1))
            y = self.d2(torch.cat([up(y, scale_factor=2.0, mode="nearest"), b], 1))
            return self.head(y)

    return KeypointNet()


def train(data: dict, minutes: float, seed: int, out: Path, batch: int = 16) -> None:
    import torch

    torch.manual_seed(seed)
    torch.set_num_threads(2)
    rng = np.random.default_rng(seed + 1)
    model = build_model()
    n_par = sum(p.numel() for p in model.parameters())
    print(f"  model: {n_par / 1e3:.0f} K parameters", flush=True)
    opt = torch.optim.AdamW(model.parameters(), lr=3e-3, weight_decay=1e-4)
    n = len(data["img"])
    t0 = time.perf_counter()
    budget = minutes * 60.0
    step, ema = 0, None
    while True:
        el = time.perf_counter() - t0
        if el > budget:
            break
        lr = 3e-3 * 0.5 * (1 + math.cos(math.pi * min(1.0, el / budget))) + 5e-5
        for g in opt.param_groups:
            g["lr"] = lr
        idx = rng.integers(0, n, batch)
        xs, ts = [], []
        for i in idx:
            im, k = augment(data["img"][i], data["kp"][i], bool(data["cw"][i]), rng)
            xs.append(im.transpose(2, 0, 1))
            ts.append(targets(k))
        x = torch.from_numpy(np.stack(xs))
        t = torch.from_numpy(np.stack(ts)).reshape(batch, K, -1)
        logits = model(x).reshape(batch, K, -1)
        loss = -(t * torch.log_softmax(logits, -1)).sum(-1).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
        step += 1
        ema = float(loss) if ema is None else 0.98 * ema + 0.02 * float(loss)
        if step % 200 == 0:
            print(f"  step {step}  loss {ema:.3f}  lr {lr:.2e}  [{el / 60:.1f} min]", flush=True)
    print(f"  trained {step} steps of {batch} in {(time.perf_counter() - t0) / 60:.1f} min",
          flush=True)
    model.eval()
    out.parent.mkdir(parents=True, exist_ok=True)
    torch.onnx.export(model, torch.zeros(1, 3, IN, IN), str(out), opset_version=13,
                      input_names=["bgr"], output_names=["heatmaps"], dynamo=False)
    print(f"  wrote {out} ({out.stat().st_size / 1e6:.2f} MB)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n-clean", type=int, default=800)
    ap.add_argument("--n-field", type=int, default=800)
    ap.add_argument("--n-hard", type=int, default=500)
    ap.add_argument("--minutes", type=float, default=25.0, help="training wall-time budget")
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--cache", default="",
                    help="comma-separated npz files of generated samples (one is made if missing)")
    ap.add_argument("--gen-only", action="store_true")
    ap.add_argument("--out", default=str(ROOT / "app/core/meter/models/dial_keypoints.onnx"))
    args = ap.parse_args(argv)
    cv2.setNumThreads(1)
    caches = [Path(c) for c in args.cache.split(",") if c]
    if caches and all(c.exists() for c in caches):
        parts = [dict(np.load(c)) for c in caches]
        data = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    else:
        cache = caches[0] if caches else None
        t0 = time.perf_counter()
        data = generate({"clean": args.n_clean, "field": args.n_field, "hard": args.n_hard},
                        args.seed)
        print(f"  data: {len(data['img'])} samples in {(time.perf_counter() - t0) / 60:.1f} min")
        if cache is not None:
            np.savez(cache, **data)
    if args.gen_only:
        return 0
    train(data, args.minutes, args.seed, Path(args.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
