"""Torch definitions of the engine's test and benchmark models (tools/engine/make_test_models.py).

Every model is float, batch 1, fully convolutional, and written so that PyTorch's eager-mode
post-training quantization also works on it (QuantStub/DeQuantStub, FloatFunctional for
add/mul/cat; in float mode these are plain ops and export as Add/Mul/Concat), which lets
tools/engine/bench_torch.py run PyTorch's own int8 on exactly the same architecture.

MAC counting (``count_macs``): Conv: Cout*Hout*Wout*Cin/groups*kh*kw; ConvTranspose:
Cin*Hin*Win*Cout/groups*kh*kw; other ops count 0.
"""

from __future__ import annotations

from typing import Dict, List, Sequence, Tuple

import torch
import torch.nn as nn
import torch.nn.functional as F
from torch.ao.nn.quantized import FloatFunctional
from torch.ao.quantization import DeQuantStub, QuantStub


def conv(cin: int, cout: int, k: int = 3, stride: int = 1, groups: int = 1, dilation: int = 1,
         relu: bool = True) -> nn.Sequential:
    """Conv2d (+ ReLU) with 'same' padding for odd kernels, as a fusable Sequential."""
    layers: List[nn.Module] = [nn.Conv2d(cin, cout, k, stride, padding=dilation * (k // 2),
                                         dilation=dilation, groups=groups, bias=True)]
    if relu:
        layers.append(nn.ReLU())
    return nn.Sequential(*layers)


def init_weights(model: nn.Module, seed: int) -> nn.Module:
    """He-normal weights (activations keep their scale through depth), small random biases."""
    g = torch.Generator().manual_seed(seed)
    for m in model.modules():
        if isinstance(m, (nn.Conv2d, nn.ConvTranspose2d)):
            fan_in = m.weight[0].numel() if isinstance(m, nn.Conv2d) else (
                m.weight.shape[0] // m.groups * m.weight.shape[2] * m.weight.shape[3])
            std = (2.0 / fan_in) ** 0.5
            with torch.no_grad():
                m.weight.copy_(torch.randn(m.weight.shape, generator=g) * std)
                if m.bias is not None:
                    m.bias.copy_((torch.rand(m.bias.shape, generator=g) - 0.5) * 0.2)
    return model.eval()


class ConvBlocks(nn.Module):
    """conv_blocks: Conv3x3+Relu, strided Conv, depthwise Conv+Clip(0,6), pointwise linear Conv,
    dilated Conv, grouped Conv (groups 4), residual Add+Relu, Sigmoid gate and Mul (same shape),
    plain Add. Input [1,3,64,64] -> output 'features' [1,8,32,32]."""

    input_shape = (1, 3, 64, 64)
    output_names = ["features"]

    def __init__(self):
        super().__init__()
        self.quant, self.dequant = QuantStub(), DeQuantStub()
        self.stem = conv(3, 16)                                  # Conv 3x3 + Relu
        self.down = conv(16, 32, stride=2)                       # strided Conv + Relu
        self.dw = nn.Conv2d(32, 32, 3, 1, 1, groups=32)          # depthwise
        self.dw_act = nn.ReLU6()                                 # -> Clip(0, 6)
        self.pw = conv(32, 32, k=1, relu=False)                  # pointwise, linear
        self.dil = conv(32, 32, dilation=2)                      # dilated Conv + Relu
        self.grp = conv(32, 32, groups=4, relu=False)            # grouped Conv
        self.res_relu = nn.ReLU()
        self.res_add = FloatFunctional()                         # Add + Relu
        self.gate = conv(32, 32, k=1, relu=False)
        self.gate_mul = FloatFunctional()                        # Mul (same shape)
        self.mix = conv(32, 32, k=3, relu=False)
        self.skip_add = FloatFunctional()                        # plain Add
        self.head = conv(32, 8, relu=False)

    def forward(self, x):
        x = self.quant(x)
        a = self.stem(x)
        b = self.down(a)
        c = self.pw(self.dw_act(self.dw(b)))
        d = self.grp(self.dil(c))
        e = self.res_relu(self.res_add.add(d, c))
        f = self.gate_mul.mul(e, torch.sigmoid(self.gate(e)))
        g = self.skip_add.add(self.mix(f), b)
        return self.dequant(self.head(g))


class FpnHeads(nn.Module):
    """fpn_heads: a small detector. Non-square input [1,3,64,96] (H=64, W=96).
    Backbone: 4 strided Conv+Relu (strides 2, 4, 8, 16). ConvTranspose k4 s2 p1 (stride 16 ->
    8) + Add + Relu; MaxPool 2x2 on a stride-2 branch; Resize bilinear x2 (half_pixel) and
    ConvTranspose k2 s2 (stride 8 -> 4); Concat of three branches, Concat of two branches.
    Heads at stride 4 (16 x 24): 'objectness' (Sigmoid, 1 ch), 'regression' (linear, 4 ch),
    'class_scores' (Sigmoid, 3 ch)."""

    input_shape = (1, 3, 64, 96)
    output_names = ["objectness", "regression", "class_scores"]

    def __init__(self):
        super().__init__()
        self.quant = QuantStub()
        self.dq_obj, self.dq_reg, self.dq_cls = DeQuantStub(), DeQuantStub(), DeQuantStub()
        self.c2 = conv(3, 16, stride=2)
        self.c4 = conv(16, 24, stride=2)
        self.c8 = conv(24, 32, stride=2)
        self.c16 = conv(32, 48, stride=2)
        self.up16 = nn.ConvTranspose2d(48, 32, 4, stride=2, padding=1)   # k4 s2 p1
        self.p8_add = FloatFunctional()
        self.p8_relu = nn.ReLU()
        self.side = conv(16, 16)
        self.pool = nn.MaxPool2d(2, 2)                                   # MaxPool 2x2
        self.up8 = nn.ConvTranspose2d(32, 16, 2, stride=2)               # k2 s2
        self.cat3 = FloatFunctional()
        self.lat = conv(24 + 32 + 16, 32, k=1)
        self.cat2 = FloatFunctional()
        self.neck = conv(32 + 16, 32)
        self.obj = nn.Conv2d(32, 1, 1)
        self.reg = nn.Conv2d(32, 4, 1)
        self.cls = nn.Conv2d(32, 3, 1)

    def forward(self, x):
        x = self.quant(x)
        c2 = self.c2(x)
        c4 = self.c4(c2)
        c8 = self.c8(c4)
        c16 = self.c16(c8)
        p8 = self.p8_relu(self.p8_add.add(c8, self.up16(c16)))
        m4 = self.pool(self.side(c2))
        r4 = F.interpolate(p8, scale_factor=2.0, mode="bilinear", align_corners=False)
        t4 = self.up8(p8)
        f4 = self.lat(self.cat3.cat([c4, r4, t4], dim=1))
        h = self.neck(self.cat2.cat([f4, m4], dim=1))
        return (self.dq_obj(torch.sigmoid(self.obj(h))), self.dq_reg(self.reg(h)),
                self.dq_cls(torch.sigmoid(self.cls(h))))


class Classifier(nn.Module):
    """classifier: 3 strided Conv+Relu, GlobalAveragePool, 1x1 Conv -> 'logits' [1,10,1,1].
    Input [1,3,64,64]."""

    input_shape = (1, 3, 64, 64)
    output_names = ["logits"]

    def __init__(self):
        super().__init__()
        self.quant, self.dequant = QuantStub(), DeQuantStub()
        self.features = nn.Sequential(conv(3, 16, stride=2), conv(16, 32, stride=2),
                                      conv(32, 64, stride=2))
        self.fc = nn.Conv2d(64, 10, 1)

    def forward(self, x):
        x = self.quant(x)
        x = self.features(x)
        x = F.adaptive_avg_pool2d(x, 1)  # exports as GlobalAveragePool
        return self.dequant(self.fc(x))


class InvertedResidual(nn.Module):
    def __init__(self, cin: int, cout: int, stride: int, expand: int):
        super().__init__()
        hidden = cin * expand
        layers: List[nn.Module] = []
        if expand != 1:
            layers.append(conv(cin, hidden, k=1))
        layers += [conv(hidden, hidden, stride=stride, groups=hidden), conv(hidden, cout, k=1,
                                                                            relu=False)]
        self.body = nn.Sequential(*layers)
        self.use_res = stride == 1 and cin == cout
        self.add = FloatFunctional()

    def forward(self, x):
        y = self.body(x)
        return self.add.add(x, y) if self.use_res else y


class MobileNetV2Backbone(nn.Module):
    """Benchmark model: MobileNetV2 (width 1.0) feature extractor, ReLU instead of ReLU6 (so
    that torch eager quantization fuses Conv+ReLU the same way the engine fuses Conv+Relu),
    no BatchNorm (folded), 512x512 input -> 'features' [1,1280,16,16]. About 1.6 GMAC."""

    output_names = ["features"]
    CFG = [(1, 16, 1, 1), (6, 24, 2, 2), (6, 32, 3, 2), (6, 64, 4, 2), (6, 96, 3, 1),
           (6, 160, 3, 2), (6, 320, 1, 1)]  # expand, channels, repeats, first stride

    def __init__(self, size: int = 512):
        super().__init__()
        self.input_shape = (1, 3, size, size)
        self.quant, self.dequant = QuantStub(), DeQuantStub()
        layers: List[nn.Module] = [conv(3, 32, stride=2)]
        cin = 32
        for t, c, n, s in self.CFG:
            for i in range(n):
                layers.append(InvertedResidual(cin, c, s if i == 0 else 1, t))
                cin = c
        layers.append(conv(cin, 1280, k=1))
        self.features = nn.Sequential(*layers)

    def forward(self, x):
        return self.dequant(self.features(self.quant(x)))


TEST_MODELS = {"conv_blocks": ConvBlocks, "fpn_heads": FpnHeads, "classifier": Classifier}


def build(name: str, seed: int = 0) -> nn.Module:
    """The model ``name`` ('conv_blocks', 'fpn_heads', 'classifier', 'bench') with its fixed
    deterministic weights (seed 0 is the one used for the committed files)."""
    model = MobileNetV2Backbone() if name == "bench" else TEST_MODELS[name]()
    model = init_weights(model, seed + {"conv_blocks": 1, "fpn_heads": 2, "classifier": 3,
                                        "bench": 4}[name])
    if name == "bench":  # keep activations bounded without BatchNorm: damp linear projections
        with torch.no_grad():
            for m in model.modules():
                if isinstance(m, InvertedResidual):
                    m.body[-1][0].weight.mul_(0.5 if m.use_res else 0.7)
    return model


def count_macs(model: nn.Module, input_shape: Sequence[int]) -> Tuple[int, Dict[str, int]]:
    """Multiply-accumulates of one forward pass, total and per layer (forward hooks)."""
    per_layer: Dict[str, int] = {}
    hooks = []
    for name, m in model.named_modules():
        if isinstance(m, (nn.Conv2d, nn.ConvTranspose2d)):
            def hook(mod, inp, out, name=name):
                kh, kw = mod.kernel_size
                if isinstance(mod, nn.Conv2d):
                    n = out.shape[1] * out.shape[2] * out.shape[3] * mod.in_channels // mod.groups
                else:
                    n = inp[0].shape[1] * inp[0].shape[2] * inp[0].shape[3] * \
                        mod.out_channels // mod.groups
                per_layer[name] = int(n * kh * kw)
            hooks.append(m.register_forward_hook(hook))
    with torch.no_grad():
        model(torch.zeros(*input_shape))
    for h in hooks:
        h.remove()
    return sum(per_layer.values()), per_layer


def fuse_conv_relu(model: nn.Module) -> nn.Module:
    """torch.ao.quantization.fuse_modules on every Sequential(Conv2d, ReLU) made by ``conv``."""
    from torch.ao.quantization import fuse_modules

    for name, m in list(model.named_modules()):
        if (isinstance(m, nn.Sequential) and len(m) == 2 and isinstance(m[0], nn.Conv2d)
                and isinstance(m[1], nn.ReLU)):
            fuse_modules(m, [["0", "1"]], inplace=True)
    return model
