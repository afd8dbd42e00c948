"""``splineimu batch``: Monte-Carlo runs of a scene file on a Dask cluster."""

from __future__ import annotations

NAME = "batch"
ORDER = 16
HELP = "run N seeded variants of a scene file (its vary: block) on a local or existing Dask cluster"
DESCRIPTION = """\
Run N variants of a scene file: run k draws the values of the file's `vary:` block and its own
seed from the file's `seed` and k alone, so any run can be repeated on its own with
`splineimu run SCENE.yaml --run-index k -o DIR` (same bytes).

  seed: 42
  vary:
    imu.model.gyroscope_noise_density: {normal: [1.8e-4, 2.0e-5]}
    imu.model.accelerometer_noise_density: {uniform: [1.0e-3, 3.0e-3]}
    imu.extrinsic.translation.0: {choice: [0.0, 0.05, 0.1]}

Output: OUT/runs/NNNNN/ (00000, 00001, ...: each what `splineimu run` writes), OUT/runs.csv
(run, seed, the drawn values at full precision, status, error) and OUT/batch.json. Each run
folder appears complete or not at all; --resume runs the missing ones. The exit code is 1 if a
run failed (its reason is in runs.csv). The files reach the disk at the end of the batch (one
sync, not one per file): after a power loss during a batch, --resume re-checks the run folders
that runs.csv does not list as ok.

By default a local Dask cluster of --workers processes runs the batch. With --scheduler the
runs go to an existing cluster (`dask scheduler` + `dask worker`, dask-jobqueue, Kubernetes):
OUT, and any file the scene names, must then be reachable by every worker at the same path.

examples:
  splineimu batch examples/batch_scene.yaml --runs 100 -o mc
  splineimu batch examples/batch_scene.yaml --runs 1000 -o mc --resume
  splineimu batch scene.yaml --runs 5000 -o /shared/mc --scheduler tcp://10.0.0.5:8786
"""


def add_arguments(p):
    p.add_argument("scene_file", metavar="SCENE.yaml", help="scene file with a seed and a vary: block")
    p.add_argument("--runs", "-n", type=int, required=True, metavar="N", help="number of runs (0 .. N-1)")
    p.add_argument("-o", "--out", required=True, metavar="OUT",
                   help="batch folder; with --scheduler it must be reachable by the workers at this path")
    p.add_argument("--workers", type=int, metavar="K",
                   help="worker processes of the local cluster, one thread each (default: one per core)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run on an existing Dask cluster (tcp://HOST:PORT) instead of a local one; "
                        "OUT must be reachable by its workers")
    p.add_argument("--resume", action="store_true", help="continue the batch in OUT: run only the missing runs")
    p.add_argument("--force", action="store_true", help="replace an existing OUT")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def run(args) -> int:
    import sys

    from ..api.batch import run_batch
    from ._common import say

    if args.workers is not None and args.scheduler:
        from ..errors import ConfigError

        raise ConfigError("--workers is for the local cluster; an existing cluster (--scheduler) has its own",
                          option="--workers")
    result = run_batch(args.scene_file, args.runs, args.out, workers=args.workers, scheduler=args.scheduler,
                       resume=args.resume, force=args.force,
                       progress=not args.no_progress and sys.stderr.isatty(), echo=say)
    for line in result.summary():
        say(line)
    return 0 if result.ok else 1
