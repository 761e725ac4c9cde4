"""The dial keypoint network (bench/train_keypoints.py; read by app.core.meter.keypoints):
a small U-Net, 128 x 128 BGR in, four 32 x 32 heatmap logits out (stride 4), its
export to ONNX and its loading back from an exported file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

IN = 128  # network input
OUT = 32  # heatmap side (stride 4)
K = 4  # pivot, tip, min end mark, max end mark
NAMES = ("pivot", "tip", "min", "max")

WIDE = (16, 32, 64, 128)  # encoder widths of a new network (0.50 M parameters)
FIRST = (16, 24, 48, 96)  # those of the first committed network (0.30 M), for --init


def build_model(widths: tuple[int, ...] = WIDE, norm: bool = True):
    """The network; ``norm=False``: plain convolutions with a bias in place of convolution
    and batch norm (what an exported network holds, BN folded in: so it can be trained on)."""
    import torch
    from torch import nn

    def cbr(i, o, s=1, d=1, k=3):
        if not norm:
            return nn.Sequential(nn.Conv2d(i, o, k, s, d * (k // 2), dilation=d),
                                 nn.ReLU(inplace=True))
        return nn.Sequential(nn.Conv2d(i, o, k, s, d * (k // 2), dilation=d, bias=False),
                             nn.BatchNorm2d(o), nn.ReLU(inplace=True))

    w1, w2, w3, w4 = widths

    class KeypointNet(nn.Module):
        """Small U-Net: 128 -> 64 -> 32 -> 16 -> 8, decoded back to 32 (stride 4)."""

        def __init__(self):
            super().__init__()
            self.e1 = cbr(3, w1, 2)  # 64
            self.e2 = nn.Sequential(cbr(w1, w2, 2), cbr(w2, w2))  # 32
            self.e3 = nn.Sequential(cbr(w2, w3, 2), cbr(w3, w3))  # 16
            self.e4 = nn.Sequential(cbr(w3, w4, 2), cbr(w4, w4), cbr(w4, w4, d=2))  # 8
            self.d3 = nn.Sequential(cbr(w4 + w3, w3, k=1), cbr(w3, w3))
            self.d2 = nn.Sequential(cbr(w3 + w2, 32, k=1), cbr(32, 32))
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


def load_exported(path: Path):
    """A trainable network (:data:`FIRST` widths, no batch norm) holding the weights of an
    exported ONNX file of that shape: its convolutions, in graph order, are the model's."""
    import onnx
    import torch
    from onnx import numpy_helper

    g = onnx.load(str(path)).graph
    init = {i.name: numpy_helper.to_array(i) for i in g.initializer}
    convs = [n for n in g.node if n.op_type == "Conv"]
    model = build_model(FIRST, norm=False)
    mods = [m for m in model.modules() if isinstance(m, torch.nn.Conv2d)]
    if len(mods) != len(convs):
        raise ValueError(f"{path.name}: {len(convs)} convolutions, the model has {len(mods)}")
    with torch.no_grad():
        for m, n in zip(mods, convs, strict=True):
            w, b = init[n.input[1]], init[n.input[2]]
            if tuple(m.weight.shape) != w.shape:
                raise ValueError(f"{path.name}: {w.shape} where the model has {m.weight.shape}")
            m.weight.copy_(torch.from_numpy(w))
            m.bias.copy_(torch.from_numpy(b))
    return model


def export(model, out: Path) -> None:
    """The network to ONNX (opset 13, read by OpenCV's dnn module), in eval mode."""
    import torch

    was = model.training
    model.eval()
    out.parent.mkdir(parents=True, exist_ok=True)
    with torch.no_grad():
        torch.onnx.export(model, torch.zeros(1, 3, IN, IN), str(out), opset_version=13,
                          input_names=["bgr"], output_names=["heatmaps"], dynamo=False)
    model.train(was)


def decode_argmax(logits) -> np.ndarray:
    """Each heatmap's peak cell as a point in input pixels (for the validation figure)."""
    b, k = logits.shape[:2]
    idx = logits.reshape(b, k, -1).argmax(-1).numpy()
    return np.stack([(idx % OUT + 0.5) * IN / OUT, (idx // OUT + 0.5) * IN / OUT], -1)
