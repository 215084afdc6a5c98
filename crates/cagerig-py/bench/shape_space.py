"""Variants per second of the shape-space exploration (cagerig.shape_space) on a local Dask
cluster with 1 and 2 worker processes (one thread each, RAYON_NUM_THREADS=1 so that a worker
is one core, and glibc's default malloc settings: see shape_space.DASK_CONFIG), after a warm-up batch that loads the rig in every worker; with the files written
(each OBJ goes through the library's atomic write: temporary file, fsync, rename) and without
(the edits alone).

    python crates/cagerig-py/bench/shape_space.py [mesh or builtin:NAME] [--variants N]
"""

import argparse
import tempfile
import time
from pathlib import Path

import dask
import distributed

from cagerig import shape_space

ARM = Path(__file__).resolve().parents[3] / "data/arm/arm.obj"




def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("source", nargs="?", default=str(ARM))
    parser.add_argument("--variants", type=int, default=200)
    parser.add_argument("--workers", default="1,2")
    parser.add_argument("--batch", type=int, default=16, help="variants per distributed task")
    parser.add_argument("--dask-malloc-trim", action="store_true",
                        help="keep Dask's MALLOC_TRIM_THRESHOLD_=65536 in the workers")
    args = parser.parse_args()
    print(f"{args.source}: {args.variants} variants per run, bounds {shape_space.Bounds()}")
    in_process = None
    with tempfile.TemporaryDirectory() as tmp:
        shape_space.explore(args.source, 4, tmp)  # warm-up (loads the rig in this process)
        start = time.perf_counter()
        results = shape_space.explore(args.source, args.variants, tmp, first_seed=10_000)
        in_process = args.variants / (time.perf_counter() - start)
        task = sum(r["seconds"] for r in results) / len(results)
        print(f"in-process loop (rayon on all cores), files written: {in_process:.1f} variants/s "
              f"({task * 1e3:.2f} ms per variant inside the task)")
        start = time.perf_counter()
        shape_space.explore(args.source, args.variants, None, first_seed=10_000)
        print(f"in-process loop, no files: {args.variants / (time.perf_counter() - start):.1f} variants/s")
        for workers in map(int, args.workers.split(",")):
            with dask.config.set({} if args.dask_malloc_trim else shape_space.DASK_CONFIG), distributed.LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                env={"RAYON_NUM_THREADS": "1"},
            ) as cluster, distributed.Client(cluster) as client:
                shape_space.explore(args.source, 4 * workers, tmp, client=client)  # warm-up
                for directory, what in ((tmp, "files written"), (None, "no files")):
                    start = time.perf_counter()
                    shape_space.explore(args.source, args.variants, directory, client=client,
                                        first_seed=20_000, batch=args.batch)
                    rate = args.variants / (time.perf_counter() - start)
                    print(f"dask, {workers} worker(s), {what}: {rate:.1f} variants/s")


if __name__ == "__main__":
    main()
