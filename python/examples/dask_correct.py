#!/usr/bin/env python3
"""Corrects every scenario folder under a directory on a Dask cluster (distributed), one
scenario per task, and prints a table of the figures `driftcorr correct` prints.

    PYTHONPATH=build/python python3 python/examples/dask_correct.py ../shared/datasets \\
        [--mode road2d] [--workers 2] [--scheduler tcp://host:8786] [--config params.yaml] \\
        [--json results.json]

Without --scheduler it starts a LocalCluster of --workers processes with one thread each: the
library runs one solve at a time per process (driftcorr's package docstring), so parallelism comes
from processes. With --scheduler it submits to a running cluster whose workers can import
driftcorr and read the scenario paths. Each task returns a small dict of figures (the corrected
trajectory stays on the worker unless keep_arrays=True); the exit code is 1 when a scenario could
not be read or its correction failed.
"""
import argparse
import json
import sys
import time
from pathlib import Path

import driftcorr


def find_scenarios(root, mode=None):
    """The scenario folders directly under `root` (those holding a scenario.yaml), sorted by
    name; with `mode`, only those of that mode (road2d | indoor3d)."""
    folders = sorted(p.parent for p in Path(root).glob("*/scenario.yaml"))
    if mode is not None:
        folders = [f for f in folders if driftcorr.load_scenario(f).mode == mode]
    return [str(f) for f in folders]


def correct_one(path, config=None, keep_arrays=False):
    """One task: corrects a scenario folder; a bad scenario comes back as an error, not a raise."""
    start = time.perf_counter()
    try:
        c = driftcorr.correct_scenario(path, config)
    except ValueError as e:  # driftcorr.InputError and bad arguments
        return {"path": path, "error": str(e)}
    out = {"path": path, "name": c.name, "mode": c.mode, "poses": len(c.estimate_en),
           "status": c.status, "verdict": c.verdict, "reasons": c.reasons,
           "before": c.metrics_before, "after": c.metrics_after, "timings": c.timings,
           "wall_s": time.perf_counter() - start}
    if keep_arrays:
        out.update(corrected=c.corrected, covariance=c.covariance, flags=c.flags)
    return out


def correct_all(client, paths, config=None, keep_arrays=False):
    """Maps correct_one over `paths` on the cluster behind `client`; results in path order."""
    futures = client.map(correct_one, paths, config=config, keep_arrays=keep_arrays, pure=False)
    return client.gather(futures)


def format_table(results):
    lines = [f"{'scenario':34} {'poses':>6} {'verdict':>9} {'estimate ATE / final':>22} "
             f"{'corrected ATE / final':>22} {'wall s':>7}"]
    for r in results:
        label = Path(r["path"]).name
        if "error" in r:
            lines.append(f"{label:34} error: {r['error']}")
            continue
        cells = []
        for m in (r["before"], r["after"]):
            cells.append(f"{m['ate_m']:8.2f} / {m['final_m']:8.2f} m" if m else f"{'-':>22}")
        lines.append(f"{label:34} {r['poses']:6d} {r['verdict']:>9} {cells[0]:>22} "
                     f"{cells[1]:>22} {r['wall_s']:7.2f}")
    return "\n".join(lines)


def main(argv=None):
    from distributed import Client, LocalCluster

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("root", help="directory whose sub-folders are scenarios")
    ap.add_argument("--mode", choices=["road2d", "indoor3d"], help="only scenarios of this mode")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    ap.add_argument("--scheduler", help="address of a running scheduler instead of a LocalCluster")
    ap.add_argument("--config", help="params.yaml for every scenario")
    ap.add_argument("--json", help="write the figures as JSON here")
    args = ap.parse_args(argv)

    paths = find_scenarios(args.root, args.mode)
    if not paths:
        print(f"no scenario folders under {args.root}", file=sys.stderr)
        return 1
    start = time.perf_counter()
    if args.scheduler:
        with Client(args.scheduler) as client:
            results = correct_all(client, paths, args.config)
    else:
        with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            results = correct_all(client, paths, args.config)
    print(format_table(results))
    print(f"{len(paths)} scenarios in {time.perf_counter() - start:.1f} s wall")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    bad = [r for r in results if "error" in r or r["verdict"] == "failed"]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
