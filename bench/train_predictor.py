"""Train the floor-plan predictor on generated plans and report its quality on held-back
ones (``make train-predictor``).

The training plans and their partial maps come from :mod:`bench.predictor_data` (generator
seeds :data:`~bench.predictor_data.TRAIN_SEEDS`), the evaluation plans from the disjoint
:data:`~bench.predictor_data.EVAL_SEEDS`; one ``--seed`` fixes the data, the network's
initialisation and the batches, and torch runs on ``--threads`` CPU threads, so a seed
and the same arguments give the same weights on the same torch build. The loss is the
binary cross-entropy of "free inside the building" per coarse cell, weighted by
``0.1 + unknown share`` (known cells are copied from the input; the guess is what
matters). The weights go to ``--out`` (an ``.npz``, :mod:`explore_seg.core.prediction.model`)
with the seed, the command line and the evaluation figures in its ``meta.*`` entries.

Evaluation, on the unknown coarse cells (unknown share > 0.5) inside the plan's bounds of
every held-back partial map (``all``) and on those within 1 m of a known free cell
(``near``: what a viewpoint at a frontier looks into): cross-entropy, Brier score and
accuracy at 0.5 of the network, against the constant guess (the training targets' mean
over such cells). ``--evaluate WEIGHTS`` only evaluates a weight file.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench.predictor_data import EVAL_SEEDS, crop, make_samples  # noqa: E402
from explore_seg.core.prediction.model import (DEFAULT_WIDTHS, WEIGHTS_PATH,  # noqa: E402
                                               build_unet, save_unet, stride)


def _weights(x: np.ndarray) -> np.ndarray:
    return 0.1 + x[:, 2]


def evaluate(net, plans, widths, base_rate: float | None
             ) -> dict[str, dict[str, float]]:
    """Quality on the unknown cells of ``plans``, all and near known free space (module
    docstring)."""
    import torch
    from scipy import ndimage

    s = stride(widths)
    ps: dict[str, list] = {"all": [], "near": []}
    ys: dict[str, list] = {"all": [], "near": []}
    with torch.inference_mode():
        for plan in plans:
            for x, y in zip(plan.inputs.astype(np.float32), plan.targets):
                _, h, w = x.shape
                hp, wp = -(-h // s) * s, -(-w // s) * s
                xp = np.zeros((3, hp, wp), np.float32)
                xp[2] = 1.0
                xp[:, :h, :w] = x
                logit = net(torch.from_numpy(xp)[None])[0].numpy()[:h, :w]
                m = x[2] > 0.5
                near = m & ndimage.binary_dilation(x[0] > 0.5, iterations=5)
                for key, mask in (("all", m), ("near", near)):
                    ps[key].append(1.0 / (1.0 + np.exp(-logit[mask])))
                    ys[key].append(y[mask])
    return {key: _scores(np.concatenate(ps[key]), np.concatenate(ys[key]), base_rate)
            for key in ps}


def _scores(p: np.ndarray, y: np.ndarray, base_rate: float | None) -> dict[str, float]:
    p = np.clip(p.astype(np.float64), 1e-6, 1 - 1e-6)
    y = y.astype(np.float64)
    c = np.clip(y.mean() if base_rate is None else base_rate, 1e-6, 1 - 1e-6)
    return {"cells": int(y.size), "target_mean": float(y.mean()),
            "bce": float(-(y * np.log(p) + (1 - y) * np.log(1 - p)).mean()),
            "bce_constant": float(-(y * np.log(c) + (1 - y) * np.log(1 - c)).mean()),
            "brier": float(((p - y) ** 2).mean()),
            "brier_constant": float(((c - y) ** 2).mean()),
            "accuracy": float(((p > 0.5) == (y > 0.5)).mean()),
            "accuracy_constant": float(max(y.mean(), 1 - y.mean()))}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--plans", type=int, default=120, help="training plans")
    ap.add_argument("--per-plan", type=int, default=4, help="partial maps per plan")
    ap.add_argument("--max-poses", type=int, default=40, help="most scan poses per map")
    ap.add_argument("--eval-plans", type=int, default=20)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--crop", type=int, default=64, help="training window (coarse cells)")
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--factor", type=int, default=4, help="map cells per coarse cell side")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--out", type=Path, default=WEIGHTS_PATH)
    ap.add_argument("--evaluate", type=Path, default=None,
                    help="only evaluate this weight file (its meta.base_rate, the held-back "
                         "plans of --seed)")
    args = ap.parse_args(argv)
    import torch

    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    t0 = time.process_time()
    if args.evaluate is not None:
        from explore_seg.core.prediction.model import load_unet

        net, widths, factor, meta = load_unet(args.evaluate)
        held = make_samples(args.seed + 1, args.eval_plans, 2, args.max_poses, factor,
                            seed_range=EVAL_SEEDS)
        # Without a recorded training base rate, the constant is the held-back cells' own
        # mean (the best constant there is).
        quality = evaluate(net, held, widths,
                           float(meta["base_rate"]) if "base_rate" in meta else None)
        print("held-back quality:", json.dumps(quality), flush=True)
        return 0
    train = make_samples(args.seed, args.plans, args.per_plan, args.max_poses, args.factor)
    held = make_samples(args.seed + 1, args.eval_plans, 2, args.max_poses, args.factor,
                        seed_range=EVAL_SEEDS)
    for p in train + held:   # compact while kept: fractions are multiples of 1/factor^2
        object.__setattr__(p, "inputs", p.inputs.astype(np.float16))
    print(f"data: {len(train)} training plans, {len(held)} held-back plans, "
          f"{time.process_time() - t0:.0f} CPU s", flush=True)
    unk = np.concatenate([p.targets[p.inputs[:, 2] > 0.5] for p in train])
    base_rate = float(unk.mean())
    widths = DEFAULT_WIDTHS
    net = build_unet(widths)
    opt = torch.optim.Adam(net.parameters(), lr=args.lr)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, args.steps)
    rng = np.random.default_rng(args.seed + 2)
    index = [(i, k) for i, p in enumerate(train) for k in range(len(p.inputs))]
    t1, running = time.process_time(), 0.0
    for step in range(1, args.steps + 1):
        xs, ys = [], []
        for j in rng.integers(len(index), size=args.batch):
            i, k = index[j]
            x, y = crop(train[i].inputs[k].astype(np.float32), train[i].targets[k],
                        args.crop, rng)
            xs.append(x)
            ys.append(y)
        x = torch.from_numpy(np.stack(xs))
        y = torch.from_numpy(np.stack(ys))
        loss = torch.nn.functional.binary_cross_entropy_with_logits(
            net(x), y, weight=torch.from_numpy(_weights(np.stack(xs))))
        opt.zero_grad()
        loss.backward()
        opt.step()
        sched.step()
        running = 0.98 * running + 0.02 * loss.item() if step > 1 else loss.item()
        if step % 100 == 0 or step == args.steps:
            print(f"step {step}/{args.steps} loss {running:.4f} "
                  f"{time.process_time() - t1:.0f} CPU s", flush=True)
    net.eval()
    quality = evaluate(net, held, widths, base_rate)
    print("held-back quality:", json.dumps(quality), flush=True)
    command = "bench/train_predictor.py " + shlex.join(sys.argv[1:] if argv is None else argv)
    save_unet(net, args.out, widths, args.factor,
              {"seed": args.seed, "command": command, "quality": json.dumps(quality),
               "base_rate": base_rate,
               "torch": torch.__version__})
    print(f"wrote {args.out} ({args.out.stat().st_size} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
