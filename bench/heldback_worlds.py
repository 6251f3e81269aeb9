"""Write held-back generated floor plans as world files, for paired runs of strategies
that are tuned or trained on generated plans (``foresight``'s predictor).

The plans come from :func:`sim_bridge.worlds.generate_house` with generator seeds
``--first-seed`` on (default 1000: the benchmark's generated worlds use seed 1, the
predictor's training plans :data:`bench.predictor_data.TRAIN_SEEDS`), the 20 x 20 m house
size of the benchmark, plain and cluttered alternating::

    .venv/bin/python bench/heldback_worlds.py --out out/heldback_worlds --count 6
    .venv/bin/python bench/paired.py --worlds out/heldback_worlds/house_s1000.world.yaml,...
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from sim_bridge.worlds import generate_house, save_world  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--count", type=int, default=6)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    paths = []
    for i in range(args.count):
        seed = args.first_seed + i
        cluttered = i % 2 == 1
        world = generate_house(seed, cluttered=cluttered)
        path = args.out / f"house{'_cluttered' if cluttered else ''}_s{seed}.world.yaml"
        save_world(world, path)
        paths.append(str(path))
    print(",".join(paths))
    return 0


if __name__ == "__main__":
    sys.exit(main())
