#!/usr/bin/python3
"""Driver of the terracut DEM reference data (LIGGGHTS-PUBLIC 3.8).

  run.py material --seeds 1 2 3          material tests -> results/material.json
  run.py material ... --scheduler ADDR   the same, the tests side by side on a Dask cluster
  run.py material ... --local-workers N  the same on a local Dask cluster of N processes
  run.py bed --seed 1                    pour the bulldozing bed of a seed (cached in work/)
  run.py bulldoze --case NAME --seed 1   one bulldozing run -> results/bulldoze/NAME/seed1/
  run.py bulldoze --case all --seed 1    every case of a seed
  run.py summary [--recompute]           results/bulldoze/summary.csv from the runs present
  run.py all                             everything, seeds 1 2 3
  run.py smoke                           every script, a few hundred steps on tiny beds (CI)
  run.py digest                          markdown tables of the bulldozing summary and costs

LIGGGHTS runs one process at a time under `nice -n 19`; scratch goes to
validation/dem/work/ (git-ignored).  Use /usr/bin/python3 (numpy, scipy)."""

import argparse
import os
import shutil
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "common"))
sys.path.insert(0, os.path.join(HERE, "material"))
sys.path.insert(0, os.path.join(HERE, "bulldoze"))

import dem  # noqa: E402
import material  # noqa: E402
import bulldoze  # noqa: E402


def _material_test_on_worker(here, test, smoke):
    # Runs on a Dask worker (pickled by value from this script): the worker
    # imports the material module from the same checkout, so a cluster's
    # workers need this folder at the same path (a shared file system).
    for sub in ("common", "material"):
        path = os.path.join(here, sub)
        if path not in sys.path:
            sys.path.insert(0, path)
    import material as m
    return m.run_test(test, smoke)


def dask_map_tests(client, smoke):
    """A map_tests for material.run_all that runs each test as a task of the
    Dask cluster behind client (the same kind of cluster terracut.sweep
    uses), in the order given."""
    def map_tests(tests):
        futures = [client.submit(_material_test_on_worker, HERE, t, smoke, pure=False) for t in tests]
        return client.gather(futures)
    return map_tests


def material_client(a):
    """A dask.distributed Client for --scheduler ADDR or --local-workers N, or
    None (the tests then run here, one after the other)."""
    if not (a.scheduler or a.local_workers):
        return None
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        sys.exit("run.py material: --scheduler/--local-workers need Dask's distributed "
                 "(Debian: python3-distributed)")
    if a.scheduler:
        return Client(a.scheduler)
    if a.local_workers < 1:
        sys.exit("run.py material: --local-workers must be at least 1, got %d" % a.local_workers)
    cluster = LocalCluster(n_workers=a.local_workers, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    return Client(cluster)


def cmd_material(a):
    client = material_client(a)
    try:
        out = material.run_all(a.seeds, map_tests=dask_map_tests(client, False) if client else None)
    finally:
        if client is not None:
            client.close()
    for k in ("repose_deg", "bulk_density_kg_per_m3", "internal_friction_peak_deg",
              "internal_friction_residual_deg", "cohesion_pa", "soil_tool_friction_deg"):
        print(k, out[k], out[k + "_per_seed"])


def cmd_bed(a):
    info = bulldoze.make_bed(a.seed, force=a.force)
    print({k: info[k] for k in ("particles", "initial_surface_mean_m", "bulk_density_kg_per_m3", "wall_s")})


def cmd_bulldoze(a):
    cases = list(bulldoze.CASES) if a.case == "all" else [a.case]
    for c in cases:
        if c not in bulldoze.CASES:
            sys.exit("unknown case %s (known: %s)" % (c, ", ".join(bulldoze.CASES)))
    for c in cases:
        info = bulldoze.run_case(c, a.seed, force=a.force)
        for m in info["metrics"]:
            print(c, a.seed, "%.1f-%.1f m: fx %.1f N fz %.1f N pile %.2e m3 peak %.3f m" % (
                m["window_start_m"], m["window_end_m"], m["fx_mean_n"], m["fz_mean_n"],
                m["pile_volume_m3"], m["pile_peak_height_m"]))
        bulldoze.write_summary()


def cmd_summary(a):
    if a.recompute:
        for c in bulldoze.CASES:
            for s in range(1, 100):
                if os.path.exists(os.path.join(bulldoze.RES, c, "seed%d" % s, "run.json")):
                    bulldoze.recompute_metrics(c, s)
    print(bulldoze.write_summary())


def cmd_digest(a):
    """Markdown tables of summary.csv and costs.csv (for the README)."""
    import csv
    rows = list(csv.DictReader(l for l in open(os.path.join(dem.RESULTS, "bulldoze", "summary.csv"))
                               if not l.startswith("#")))
    print("| case | window (m) | fx mean (N) | fx std (N) | fz mean (N) | fz std (N) | pile volume (m^3) "
          "| pile peak (m) | seeds |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    by = {}
    for r in rows:
        by.setdefault((r["case"], r["window_start_m"], r["window_end_m"]), {})[r["seed"]] = r
    for (c, w0, w1), d in by.items():
        m, sd = d.get("mean"), d.get("std")
        if not m:
            continue
        print("| `%s` | %s-%s | %.1f | %.1f | %.1f | %.1f | %.2e +- %.1e | %.3f +- %.3f | %s |" % (
            c, w0, w1, float(m["fx_mean_n"]), float(sd["fx_mean_n"]), float(m["fz_mean_n"]),
            float(sd["fz_mean_n"]), float(m["pile_volume_m3"]), float(sd["pile_volume_m3"]),
            float(m["pile_peak_height_m"]), float(sd["pile_peak_height_m"]), m["n_seeds"]))
    print()
    print("| kind | run | wall-clock (s) | note |")
    print("| --- | --- | --- | --- |")
    for r in csv.DictReader(open(os.path.join(dem.RESULTS, "costs.csv"))):
        if r["kind"].startswith("bulldoze"):
            print("| %s | %s | %s | %s |" % (r["kind"], r["tag"], r["wall_s"], r["note"]))


def cmd_all(a):
    material.run_all([1, 2, 3])
    for s in (1, 2, 3):
        for c in bulldoze.CASES:
            bulldoze.run_case(c, s, force=a.force)
            bulldoze.write_summary()


def cmd_smoke(a):
    """Every LIGGGHTS script and every post-processing step on tiny beds for
    a few hundred steps.  Exit status non-zero on any failure."""
    t0 = time.time()
    sm = os.path.join(dem.WORK, "bulldoze", "smoke")
    shutil.rmtree(sm, ignore_errors=True)
    shutil.rmtree(os.path.join(dem.WORK, "material", "smoke"), ignore_errors=True)
    print("LIGGGHTS", dem.liggghts_version())
    here = material.run_all([1], smoke=True)
    print("material scripts ok (%.1f s)" % (time.time() - t0))
    # The same tests as tasks of a local Dask cluster give the same results.
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        print("Dask's distributed not installed: the material tests on a cluster are not checked")
    else:
        shutil.rmtree(os.path.join(dem.WORK, "material", "smoke"), ignore_errors=True)
        with LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            there = material.run_all([1], smoke=True, map_tests=dask_map_tests(client, True))
        for k in ("repose_deg", "bulk_density_kg_per_m3", "internal_friction_peak_deg",
                  "cohesion_pa", "soil_tool_friction_deg"):
            a, b = here[k], there[k]
            assert a == b or (a != a and b != b), (k, a, b)  # equal, or both NaN (too short a smoke)
        print("material tests on a Dask cluster ok (%.1f s)" % (time.time() - t0))
    for c in ("vertical_w012_d050", "raked45_w012_d050"):
        info = bulldoze.run_case(c, 1, smoke=True)
        assert len(info["metrics"]) == 3
    print("bulldoze scripts ok (%.1f s)" % (time.time() - t0))
    chk = dem.rayleigh_check()
    assert chk["ok"], chk
    print("smoke ok in %.1f s" % (time.time() - t0))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    m = sub.add_parser("material")
    m.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    m.add_argument("--scheduler", help="a Dask scheduler's address: the tests run on its cluster")
    m.add_argument("--local-workers", type=int, default=0,
                   help="run the tests on a local Dask cluster of this many processes")
    m.set_defaults(fn=cmd_material)
    b = sub.add_parser("bed")
    b.add_argument("--seed", type=int, required=True)
    b.add_argument("--force", action="store_true", help="pour again even if cached")
    b.set_defaults(fn=cmd_bed)
    b = sub.add_parser("bulldoze")
    b.add_argument("--case", required=True, help="case name or 'all'")
    b.add_argument("--seed", type=int, required=True)
    b.add_argument("--force", action="store_true", help="rerun even if results exist")
    b.set_defaults(fn=cmd_bulldoze)
    s = sub.add_parser("summary")
    s.add_argument("--recompute", action="store_true",
                   help="recompute every run's window metrics from its files and work/ dumps first")
    s.set_defaults(fn=cmd_summary)
    s = sub.add_parser("all")
    s.add_argument("--force", action="store_true")
    s.set_defaults(fn=cmd_all)
    s = sub.add_parser("digest")
    s.set_defaults(fn=cmd_digest)
    s = sub.add_parser("smoke")
    s.set_defaults(fn=cmd_smoke)
    a = p.parse_args()
    try:
        a.fn(a)
    except dem.LiggghtsError as e:
        print(e, file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
