"""The report's cause tables: contacts by cause and runs that ended below the target.

Both read the run records' ``contacts`` (:func:`sim_bridge.contacts.classify_contact`) and
``early_stop`` (:func:`sim_bridge.early_stop.explain_stop`). Records made before those
existed (``runs.jsonl.gz`` rows, rows rebuilt from ``runs.csv``) have neither: their
contacts are counted as ``unclassified`` and their early stops as ``unexplained``, so old
and new runs report side by side.

Usage: ``.venv/bin/python bench/causes.py OUT [OUT ...]`` prints both tables for the runs of
one or more benchmark folders.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench import records  # noqa: E402
from bench.records import as_float, by_world_strategy  # noqa: E402
from sim_bridge.contacts import CONTACT_CAUSES  # noqa: E402

UNCLASSIFIED = "unclassified"
UNEXPLAINED = "unexplained"


def _sep(head: str) -> str:
    return "|" + "|".join(["---"] * (head.count("|") - 1)) + "|"


def contact_causes(r: dict[str, Any]) -> Counter[str]:
    """Contacts of one run per cause; contacts the record does not classify (older
    records) count as ``unclassified``."""
    c = Counter(x.get("cause", UNCLASSIFIED) for x in r.get("contacts") or [])
    rest = int(r.get("collisions") or 0) - sum(c.values())
    if rest > 0:
        c[UNCLASSIFIED] += rest
    return c


def contacts_table(runs: list[dict[str, Any]]) -> list[str]:
    """Markdown: per world x strategy with contacts, their number per cause, how many
    happened while backing off, the mean |speed| and the classes / objects hit."""
    groups = by_world_strategy(runs)
    per = {k: [contact_causes(r) for r in rs] for k, rs in groups.items()}
    seen = [c for cs in per.values() for ct in cs for c in ct]
    causes = [c for c in CONTACT_CAUSES + (UNCLASSIFIED,) if c in seen]
    causes += sorted(set(seen) - set(causes))
    if not causes:
        return []
    head = ("| world | strategy | runs | contacts | " + " | ".join(causes)
            + " | backing off | mean speed [m/s] | hit (class: object ×n) |")
    lines = [head, _sep(head)]
    for (world, strat), rs in groups.items():
        tot = sum(per[(world, strat)], Counter())
        if not sum(tot.values()):
            continue
        cs = [x for r in rs for x in r.get("contacts") or []]
        speed = (f"{np.mean([abs(float(x.get('speed_mps') or 0.0)) for x in cs]):.2f}"
                 if cs else "-")
        hit = Counter(f"{x.get('cls', '?')}: {x.get('object') or '?'}" for x in cs)
        # older records name what was hit in collision_places only
        hit.update(f"{pl[2]}" for r in rs if not r.get("contacts")
                   for pl in r.get("collision_places") or [] if len(pl) > 2)
        hit_txt = ", ".join(f"{k} ×{v}" for k, v in hit.most_common(4))
        if len(hit) > 4:
            hit_txt += f", +{len(hit) - 4} more"
        lines.append(f"| {world} | {strat} | {len(rs)} | {sum(tot.values())} | "
                     + " | ".join(str(tot.get(c, 0)) for c in causes)
                     + f" | {sum(1 for x in cs if x.get('backing'))} | {speed} | {hit_txt or '-'} |")
    return lines if len(lines) > 2 else []


def stop_cause(r: dict[str, Any]) -> str:
    """The cause of a run below its target (the cause of its largest unseen gap), or
    ``unexplained`` for a record without the analysis."""
    es = r.get("early_stop")
    return str(es.get("cause") or UNEXPLAINED) if es else UNEXPLAINED


def early_stop_table(runs: list[dict[str, Any]]) -> list[str]:
    """Markdown: per world x strategy with runs that did not complete, how they stopped,
    the cause of each run's largest unseen gap, the frontiers left by reason and the mean
    unseen explorable area."""
    lines: list[str] = []
    head = ("| world | strategy | runs | below target (done / timeout) | cause of the largest "
            "gap (runs) | frontiers left (reason ×n) | unseen area [m²] |")
    for (world, strat), rs in by_world_strategy(runs).items():
        bad = [r for r in rs if not r.get("completed")]
        if not bad:
            continue
        done = sum(1 for r in bad if r.get("stop_reason") == "done")
        causes = Counter(stop_cause(r) for r in bad)
        fr = Counter(f.get("reason", "?") for r in bad
                     for f in (r.get("early_stop") or {}).get("frontiers") or [])
        area = [as_float((r.get("early_stop") or {}).get("missing_m2")) for r in bad]
        area_txt = (f"{np.nanmean(area):.2f}" if any(np.isfinite(a) for a in area) else "-")
        lines.append(f"| {world} | {strat} | {len(rs)} | {len(bad)} ({done} / "
                     f"{len(bad) - done}) | "
                     + ", ".join(f"{k} ×{v}" for k, v in causes.most_common())
                     + " | " + (", ".join(f"{k} ×{v}" for k, v in fr.most_common()) or "none")
                     + f" | {area_txt} |")
    return [head, _sep(head)] + lines if lines else []


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", nargs="+", help="benchmark output folders")
    a = ap.parse_args(argv)
    runs = [r for o in a.out for r in records.read(Path(o))]
    print("\n".join(["Contacts by cause:", ""] + (contacts_table(runs) or ["(none)"])
                    + ["", "Runs below the target by cause:", ""]
                    + (early_stop_table(runs) or ["(none)"])))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
