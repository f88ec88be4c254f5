"""Speed of ``imukit.torch.preintegrate`` against pypose's ``IMUPreintegrator`` (issue 19).

CPU: batch ``--batch`` (256) × ``--samples`` (1023) windows, float64 and float32, forward and
forward + backward, with and without the 9×9 covariance, in ns per sample (median of
``--repeats`` runs, the cases alternated within each repeat so that a load change hits all of
them), both libraries in the same run on the same inputs. 1023 samples, not 1000: pypose
0.9.5's ``cumops`` asks torch for ``arange(2^k, L)`` with ``2^k > L`` unless ``L = samples + 1``
is a power of two, which torch 2.15 refuses. pypose has one scheme (lie_euler, the sample held
over its step); imukit.torch runs its CPU path (``method="native"``, the Rust kernels) in both
schemes and, with ``--scan``, the torch scan.
The covariance cases give both libraries the same white noise as densities (pypose's
``gyro_cov=1e-4``, ours ``noise=[1e-2, 1e-2]``, both discretised as ``σ²/dt``); ``--per-sample``
adds imukit's rows with that noise given per sample (``gyro_cov``/``accel_cov`` (B, N, 3),
computed from ``dt`` so that their gradient reaches it), the path for learned per-sample noise.
``--only CASE`` runs one case (forward + backward, float64) and prints the process's peak
resident memory, e.g. ``--only "native lie_euler, cov"``.

CUDA (when a GPU is present): batch ``--gpu-batch`` (4096) × 1000 samples, float32 and float64,
forward and forward + backward, deltas without covariance and with it; samples per second and the
device name. Self-contained: ``python bench/bench_torch.py [--gpu-only]``.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import time
import warnings
from collections.abc import Callable

import torch

import imukit
import imukit.torch as it

warnings.filterwarnings("ignore", category=FutureWarning)  # pypose uses torch.jit.script at import


def inputs(batch: int, n: int, dtype: torch.dtype, device: str, grad: bool) -> tuple[torch.Tensor, ...]:
    g = torch.Generator().manual_seed(0)
    gyro = torch.randn(batch, n, 3, generator=g, dtype=dtype)
    accel = torch.randn(batch, n, 3, generator=g, dtype=dtype) + torch.tensor([0.0, 0.0, 9.81], dtype=dtype)
    dt = torch.full((batch, n), 0.005, dtype=dtype)
    return tuple(x.to(device).requires_grad_(grad) for x in (dt, gyro, accel))


def ours(scheme: str, cov: bool, method: str = "native", per_sample: bool = False) -> Callable[..., torch.Tensor]:
    def run(dt: torch.Tensor, gyro: torch.Tensor, accel: torch.Tensor) -> torch.Tensor:
        if not cov:
            d = it.preintegrate(dt, gyro, accel, scheme=scheme, method=method)
            return d.delta_rotation.sum() + d.delta_velocity.sum() + d.delta_position.sum()
        if per_sample:
            given = (1e-4 / dt)[..., None].expand(*dt.shape, 3)
            noise = {"gyro_cov": given, "accel_cov": given}
        else:
            noise = {"noise": torch.tensor([1e-2, 1e-2], dtype=dt.dtype)}
        d = it.preintegrate(dt, gyro, accel, scheme=scheme, return_covariance=True, method=method, **noise)
        return d.delta_velocity.sum() + d.covariance.sum()  # type: ignore[union-attr]

    return run


def pypose(cov: bool) -> Callable[..., torch.Tensor]:
    import pypose as pp

    def run(dt: torch.Tensor, gyro: torch.Tensor, accel: torch.Tensor) -> torch.Tensor:
        integ = pp.module.IMUPreintegrator(reset=True, prop_cov=cov, gravity=0.0, gyro_cov=1e-4, acc_cov=1e-4)
        out = integ.to(dt.dtype).to(dt.device)(dt[..., None], gyro, accel)
        total = out["vel"].sum() + out["pos"].sum()
        return total + out["cov"].sum() if cov else total

    return run


def time_once(f: Callable[..., torch.Tensor], args: tuple[torch.Tensor, ...], backward: bool, device: str) -> float:
    sync = torch.cuda.synchronize if device == "cuda" else (lambda: None)
    start = time.perf_counter()
    loss = f(*args)
    if backward:
        loss.backward()  # type: ignore[no-untyped-call]
    sync()
    return time.perf_counter() - start


def time_case(
    f: Callable[..., torch.Tensor], args: tuple[torch.Tensor, ...], backward: bool, repeats: int, device: str
) -> float:
    time_once(f, args, backward, device)
    return statistics.median(time_once(f, args, backward, device) for _ in range(repeats))


def cases(scan: bool, per_sample: bool = False) -> dict[str, Callable[..., torch.Tensor]]:
    out = {}
    for cov in (False, True):
        tag = "cov" if cov else "no cov"
        out[f"native lie_euler, {tag}"] = ours("lie_euler", cov)
        out[f"native midpoint, {tag}"] = ours("midpoint", cov)
        if cov and per_sample:
            out["native lie_euler, per-sample cov"] = ours("lie_euler", cov, per_sample=True)
            out["native midpoint, per-sample cov"] = ours("midpoint", cov, per_sample=True)
        if scan:
            out[f"scan lie_euler, {tag}"] = ours("lie_euler", cov, "scan")
        out[f"pypose IMUPreintegrator, {tag}"] = pypose(cov)
    return out


def cpu(batch: int, n: int, repeats: int, scan: bool, per_sample: bool) -> None:
    print(f"CPU, {torch.get_num_threads()} threads, batch {batch} × {n} samples, ns per sample")
    print(f"(median of {repeats} alternated runs, no separate warm-up; load average before: {os.getloadavg()[0]:.1f})")
    runs = cases(scan, per_sample)
    keys = [
        (name, backward, dtype)
        for name in runs
        for backward in (False, True)
        for dtype in (torch.float64, torch.float32)
    ]
    inputs_of = {(b, d): inputs(batch, n, d, "cpu", b) for b in (False, True) for d in (torch.float64, torch.float32)}
    times: dict[tuple[str, bool, torch.dtype], list[float]] = {k: [] for k in keys}
    for _ in range(repeats):
        for name, backward, dtype in keys:
            times[name, backward, dtype].append(time_once(runs[name], inputs_of[backward, dtype], backward, "cpu"))
    print(f"{'case':<48} {'float64':>10} {'float32':>10}")
    for backward in (False, True):
        for name in runs:
            cells = [
                statistics.median(times[name, backward, d]) / (batch * n) * 1e9 for d in (torch.float64, torch.float32)
            ]
            label = f"{name}, {'fwd+bwd' if backward else 'fwd'}"
            print(f"{label:<48} {cells[0]:>10.0f} {cells[1]:>10.0f}", flush=True)
    print(f"load average after: {os.getloadavg()[0]:.1f}")


def only(name: str, batch: int, n: int, repeats: int) -> None:
    f = cases(scan=True, per_sample=True)[name]
    seconds = time_case(f, inputs(batch, n, torch.float64, "cpu", True), True, repeats, "cpu")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    ns = seconds / (batch * n) * 1e9
    print(f"{name}, fwd+bwd, float64, batch {batch} × {n}: {ns:.0f} ns/sample, peak RSS {peak:.2f} GiB")


def gpu(batch: int, n: int, repeats: int) -> None:
    if not torch.cuda.is_available():
        print("CUDA: no GPU here, section skipped")
        return
    name = torch.cuda.get_device_name()
    print(f"CUDA: {name}, batch {batch} × {n} samples, samples per second (median of {repeats})")
    for dtype in (torch.float32, torch.float64):
        for cov in (False, True):
            for backward in (False, True):
                label = f"lie_euler {dtype}, {'fwd+bwd' if backward else 'fwd'}, {'cov' if cov else 'deltas only'}"
                try:
                    args = inputs(batch, n, dtype, "cuda", backward)
                    s = time_case(ours("lie_euler", cov, "scan"), args, backward, repeats, "cuda")
                except torch.cuda.OutOfMemoryError:
                    print(f"{label:<52} out of GPU memory", flush=True)
                    continue
                finally:
                    torch.cuda.empty_cache()
                peak = torch.cuda.max_memory_allocated() / 2**30
                torch.cuda.reset_peak_memory_stats()
                print(f"{label:<52} {batch * n / s:>14.3e} samples/s, peak {peak:.1f} GiB", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=256)
    parser.add_argument("--samples", type=int, default=1023)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--gpu-batch", type=int, default=4096)
    parser.add_argument("--gpu-only", action="store_true")
    parser.add_argument("--scan", action="store_true", help="also time the torch scan on CPU")
    parser.add_argument("--per-sample", action="store_true", help="also time per-sample noise covariances")
    parser.add_argument("--threads", type=int, help="torch and imukit threads (default: torch's)")
    parser.add_argument("--only", help="one case, forward + backward float64, with its peak memory")
    a = parser.parse_args()
    if a.threads:
        torch.set_num_threads(a.threads)
        imukit.set_num_threads(a.threads)
    print(f"torch {torch.__version__}")
    if a.only:
        only(a.only, a.batch, a.samples, a.repeats)
        return
    if not a.gpu_only:
        cpu(a.batch, a.samples, a.repeats, a.scan, a.per_sample)
    gpu(a.gpu_batch, 1000, a.repeats)


if __name__ == "__main__":
    main()
