"""Reader speed and memory (issue 17, item 14): an EuRoC ``imu0/data.csv``, a TUM file and a generic CSV of
``--lines`` lines (default 3 M, EuRoC's layout at 200 Hz), each read in a fresh child process.

Prints per reader: seconds (median of ``--repeats``), the child's peak RSS, the RSS of the same child
that only imports imukit, the result arrays' bytes, and (peak − import) / result. Compare two checkouts
by running the children with another interpreter (its own imukit)::

    python bench/bench_readers.py --lines 3000000
    python bench/bench_readers.py --lines 3000000 --python /path/to/other/.venv/bin/python
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

CHILD = """
import json, resource, sys, time
import numpy as np
import imukit.io as io
kind, path = sys.argv[1], sys.argv[2]
start = time.perf_counter()
if kind == "import":
    arrays = []
elif kind == "euroc":
    imu = io.read_euroc_imu(path)
    arrays = [imu.t_ns, imu.gyro, imu.accel]
elif kind == "tum":
    trajectory = io.read_tum(path)
    arrays = [trajectory.t_ns, trajectory.position, trajectory.rotation.as_quat()]
else:
    imu = io.read_imu_csv(path, time_column=0, gyro_columns=[1, 2, 3], accel_columns=[4, 5, 6], time_unit="ns")
    arrays = [imu.t_ns, imu.gyro, imu.accel]
seconds = time.perf_counter() - start
peak_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"s": seconds, "peak_mb": peak_kib / 1024, "result_mb": sum(a.nbytes for a in arrays) / 2**20}))
"""


def write_files(folder: Path, n: int) -> dict[str, Path]:
    """The three inputs, written once per ``folder`` and size (block by block: never n lines in memory)."""
    paths = {"euroc": folder / f"euroc-{n}.csv", "tum": folder / f"tum-{n}.txt", "csv": folder / f"generic-{n}.csv"}
    if all(p.exists() for p in paths.values()):
        return paths
    rng = np.random.default_rng(0)
    with paths["euroc"].open("w") as euroc, paths["tum"].open("w") as tum, paths["csv"].open("w") as csv:
        euroc.write("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],")
        euroc.write("a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n")
        csv.write("t,wx,wy,wz,ax,ay,az\n")
        for start in range(0, n, 100_000):
            m = min(100_000, n - start)
            t_ns = 1_403_636_579_758_555_392 + (start + np.arange(m)) * 5_000_000
            values = rng.normal(size=(m, 6)).round(15)
            quat = rng.normal(size=(m, 4))
            quat /= np.linalg.norm(quat, axis=1, keepdims=True)
            for ns, row, q in zip(t_ns.tolist(), values.tolist(), quat.tolist()):
                fields = ",".join(map(repr, row))
                euroc.write(f"{ns},{fields}\n")
                csv.write(f"{ns},{fields}\n")
                tum.write(f"{ns // 10**9}.{ns % 10**9:09d} {' '.join(map(repr, row[:3] + q))}\n")
    return paths


def run(python: str, kind: str, path: Path) -> dict[str, float]:
    out = subprocess.run([python, "-c", CHILD, kind, str(path)], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)  # type: ignore[no-any-return]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--lines", type=int, default=3_000_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--python", default=sys.executable, help="the interpreter (and so the imukit) to measure")
    parser.add_argument("--folder", default=tempfile.gettempdir(), help="where the input files are kept")
    parser.add_argument("--only", nargs="*", default=["euroc", "tum", "csv"])
    args = parser.parse_args()
    paths = write_files(Path(args.folder), args.lines)
    base = run(args.python, "import", paths["euroc"])["peak_mb"]
    print(f"{args.lines:,} lines, {args.python}; a child importing imukit only: {base:.0f} MB peak RSS")
    columns = f"{'MB file':>8} {'s (median)':>11} {'peak MB':>8} {'result MB':>10} {'(peak-import)/result':>21}"
    print(f"{'reader':8} {columns}")
    for kind in args.only:
        runs = [run(args.python, kind, paths[kind]) for _ in range(args.repeats)]
        seconds = float(np.median([r["s"] for r in runs]))
        peak = max(r["peak_mb"] for r in runs)
        result = runs[0]["result_mb"]
        size = paths[kind].stat().st_size / 2**20
        print(f"{kind:8} {size:8.0f} {seconds:11.2f} {peak:8.0f} {result:10.0f} {(peak - base) / result:21.2f}")


if __name__ == "__main__":
    main()
