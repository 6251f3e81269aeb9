"""Process CPU seconds of benchmark runs (bench.tasks.run_task) in the checkout on sys.path[0].
usage: issue49_cpu_runs.py OUT.jsonl world:strategy:seed ..."""
import json, sys, time, os, subprocess
root = os.getcwd(); sys.path.insert(0, root)
from bench.tasks import run_task, fix_explorer_params
from bench.worlds import load, sim_time_limit, PAPER_CAMERA_MOUNT
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
fix_explorer_params()
out = sys.argv[1]
for item in sys.argv[2:]:
    spec, strat, seed = item.split(":")
    world, gt = load(spec)
    limit = sim_time_limit(float(gt.explorable_area_m2), None)
    c0 = time.process_time(); w0 = time.time()
    r = run_task((spec, strat, int(seed), limit, None, PAPER_CAMERA_MOUNT, None))
    cpu = time.process_time() - c0
    row = dict(commit=commit, world=spec, strategy=strat, seed=int(seed), cpu_s=round(cpu, 2),
               wall_s=round(time.time() - w0, 1), load=os.getloadavg()[0],
               **{k: r.get(k) for k in ("completed", "stop_reason", "coverage_pct", "sim_time_s", "time_to_s", "collisions", "goals_blacklisted")})
    print(json.dumps(row), flush=True)
    with open(out, "a") as f: f.write(json.dumps(row) + "\n")
