"""on_bad_line="skip": every bad line is reported with its number and reason, every valid sample is kept
(bit for bit, whatever garbage surrounds it), and a skip without a report is one warning at the caller."""

from __future__ import annotations

import inspect
import itertools
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from euroc import IMU_CSV, requires_euroc
from imukit.io import ReadReport, SkippedLine, SkippedLinesWarning
from imukit.io._lines import in_order

HEADER = "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"  # noqa: E501
# Line numbers in comments; the valid samples are lines 2, 6 and 9.
EUROC_IMU = [
    HEADER,
    "1403715523912140000,0.1,0.2,0.3,9.1,9.2,9.3",
    "1403715523917140000,1,2,3,4,5",
    "1403715523922140000,1,2,x,4,5,6",
    "1403715523927140000,1,2,nan,4,5,6",
    "1403715523932140000,-0.1,-0.2,-0.3,-9.1,-9.2,-9.3",
    "1403715523932140000,9,9,9,9,9,9",
    "1403715523927140000,1,2,3,4,5,6",
    "1403715523937140000,1e-05,0.0,-0.0,1.5,2.5,3.5",
    "1403715523.94,1,2,3,4,5,6",
    "1403715523942140000,1,2,3,4",
]


def expected_euroc_skips(path: str) -> list[SkippedLine]:
    def skip(line: int, reason: str) -> SkippedLine:
        return SkippedLine(path, line, reason, EUROC_IMU[line - 1])

    fields = "expected 7 comma-separated fields (EuRoC imu0/data.csv)"
    return [
        skip(3, f"wrong column count: {fields}, got 6"),
        skip(4, f"malformed: not a number in {EUROC_IMU[3]!r}"),
        skip(5, f"non-finite: non-finite value in {EUROC_IMU[4]!r}"),
        skip(
            7,
            "duplicate stamp: time must increase strictly, but 1403715523932140000 follows 1403715523932140000 "
            "(line 6)",
        ),
        skip(
            8,
            "stamp going back: time must increase strictly, but 1403715523927140000 follows 1403715523932140000 "
            "(line 6)",
        ),
        skip(10, "malformed: timestamp '1403715523.94' is not an integer number of nanoseconds (int64)"),
        skip(11, f"wrong column count: {fields}, got 5"),
    ]


def test_euroc_imu_skip_keeps_every_valid_sample_and_reports_each_bad_line(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text("\n".join(EUROC_IMU) + "\n")
    report = ReadReport()
    imu = ik.io.read_euroc_imu(path, on_bad_line="skip", report=report)
    assert imu.t_ns is not None
    assert imu.t_ns.tolist() == [1403715523912140000, 1403715523932140000, 1403715523937140000]
    np.testing.assert_array_equal(imu.gyro, [[0.1, 0.2, 0.3], [-0.1, -0.2, -0.3], [1e-05, 0.0, -0.0]])
    np.testing.assert_array_equal(imu.accel, [[9.1, 9.2, 9.3], [-9.1, -9.2, -9.3], [1.5, 2.5, 3.5]])
    assert report.skipped == expected_euroc_skips(str(path))
    assert len(report) == 7 and report
    assert report.summary() == (
        f"7 lines skipped in {path}: 2 wrong column counts, 2 malformed, 1 non-finite, 1 duplicate stamp, "
        "1 stamp going back"
    )
    assert [s.kind for s in report.skipped] == [
        "wrong column count", "malformed", "non-finite", "duplicate stamp", "stamp going back", "malformed",
        "wrong column count",
    ]  # fmt: skip


def test_raise_mode_stops_at_the_first_bad_line(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text("\n".join(EUROC_IMU) + "\n")
    with pytest.raises(ik.io.FileFormatError, match=rf"^path: {re.escape(str(path))}, line 3: expected 7 comma"):
        ik.io.read_euroc_imu(path)
    with pytest.raises(ik.io.FileFormatError, match=r", line 3: "):
        ik.io.read_euroc_imu(path, on_bad_line="raise", report=ReadReport())


def test_skip_without_a_report_warns_once_at_the_caller(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text("\n".join(EUROC_IMU) + "\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        imu = ik.io.read_euroc_imu(path, on_bad_line="skip")
    assert len(imu) == 3
    assert [type(w.message) for w in caught] == [SkippedLinesWarning]
    assert str(caught[0].message) == ReadReport.summary(_report(expected_euroc_skips(str(path))))
    assert caught[0].filename == __file__  # stacklevel points at this call, not into imukit


def test_a_clean_file_neither_warns_nor_reports(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text("\n".join(EUROC_IMU[:2]) + "\n")
    report = ReadReport()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ik.io.read_euroc_imu(path, on_bad_line="skip", report=report)
        ik.io.read_euroc_imu(path, on_bad_line="skip")
    assert not report and len(report) == 0 and report.summary() == "no lines skipped"


def test_folder_read_reports_both_files_in_one_report(tmp_path: Path) -> None:
    (tmp_path / "imu0").mkdir()
    (tmp_path / "imu0" / "data.csv").write_text("\n".join(EUROC_IMU) + "\n")
    gt = tmp_path / "state_groundtruth_estimate0" / "data.csv"
    gt.parent.mkdir()
    good = "1403715524907143168,0.5,2.0,0.9,1,0,0,0,0,0,0,0,0,0,0,0,0"
    zero = "1403715524912143104,0.5,2.0,0.9,0,0,0,0,0,0,0,0,0,0,0,0,0"
    gt.write_text(f"#h\n{good}\n{zero}\n")
    report = ReadReport()
    imu, truth = ik.io.read_euroc(tmp_path, on_bad_line="skip", report=report)
    assert len(imu) == 3 and truth is not None and len(truth) == 1
    assert report.skipped == [
        *expected_euroc_skips(str(tmp_path / "imu0" / "data.csv")),
        SkippedLine(str(gt), 3, "zero quaternion: zero quaternion", zero),
    ]
    assert report.summary().startswith(f"8 lines skipped in {tmp_path / 'imu0' / 'data.csv'}, {gt}: ")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ik.io.read_euroc(tmp_path, on_bad_line="skip")
    assert len(caught) == 1 and str(caught[0].message).startswith("8 lines skipped in ")


def test_nothing_valid_left_is_an_error_that_counts_the_skips(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text(f"{HEADER}\n1,2,3\n1403715523922140000,1,2,x,4,5,6\n")
    with pytest.raises(
        ik.io.FileFormatError,
        match=rf"^path: {re.escape(str(path))}: no data lines \(2 lines skipped: 1 wrong column count, 1 malformed\)$",
    ):
        ik.io.read_euroc_imu(path, on_bad_line="skip", report=ReadReport())


def test_garbage_between_valid_lines_costs_no_sample(tmp_path: Path, rng: np.random.Generator) -> None:
    # A written trajectory with junk lines spliced in at random places reads back bit for bit.
    n = 300
    t_ns = 1_403_636_579_758_555_392 + np.cumsum(rng.integers(4_999_000, 5_001_000, n))
    truth = ik.Trajectory(None, rng.normal(size=(n, 3)), None, Rotation.random(n, rng=rng), t_ns=t_ns)
    path = tmp_path / "traj.txt"
    truth.write_tum(path)
    lines = path.read_text().splitlines()
    junk = ["0.5 1 2", "x y z 1 2 3 4 5", "1.0 inf 0 0 0 0 0 1", lines[0], "1.0 0 0 0 0 0 0 0"]
    where = sorted(rng.choice(np.arange(1, n), size=40, replace=False).tolist())
    out: list[str] = []
    bad_lines = []
    for k, line in enumerate(lines):
        out.append(line)
        if where and k == where[0]:
            where.pop(0)
            out.append(junk[k % len(junk)])
            bad_lines.append(len(out))
    path.write_text("\n".join(out) + "\n")
    report = ReadReport()
    back = ik.io.read_tum(path, on_bad_line="skip", report=report)
    assert back.t_ns is not None
    np.testing.assert_array_equal(back.t_ns, t_ns)
    np.testing.assert_array_equal(back.position, truth.position)
    np.testing.assert_array_equal(back.rotation.as_quat(), truth.rotation.as_quat())
    assert [s.line for s in report.skipped] == bad_lines
    assert {s.kind for s in report.skipped} <= {
        "wrong column count", "malformed", "non-finite", "stamp going back", "zero quaternion",
    }  # fmt: skip


def test_tum_skip_reports_exactly(tmp_path: Path) -> None:
    text = [
        "# t x y z qx qy qz qw",
        "1.000000000 0 0 0 0 0 0 1",
        "1.000000000 9 9 9 0 0 0 1",
        "1.100000000 1 0 0 0 0 0 0",
        "1.200000000 2 0 0 0 0 0 1",
        "1.100000000 3 0 0 0 0 0 1",
        "1.300000000 4 0 0",
    ]
    path = tmp_path / "t.txt"
    path.write_text("\n".join(text) + "\n")
    report = ReadReport()
    traj = ik.io.read_tum(path, on_bad_line="skip", report=report)
    assert traj.t_ns is not None and traj.t_ns.tolist() == [1_000_000_000, 1_200_000_000]
    np.testing.assert_array_equal(traj.position[:, 0], [0.0, 2.0])
    p = str(path)
    assert report.skipped == [
        SkippedLine(p, 3, "duplicate stamp: time must increase strictly, but 1.000000000 follows 1.000000000 "
                    "(line 2)", text[2]),
        SkippedLine(p, 4, "zero quaternion: zero quaternion", text[3]),
        SkippedLine(p, 6, "stamp going back: time must increase strictly, but 1.100000000 follows 1.200000000 "
                    "(line 5)", text[5]),
        SkippedLine(p, 7, "wrong column count: expected 8 fields 'timestamp tx ty tz qx qy qz qw', got 4", text[6]),
    ]  # fmt: skip


def test_report_str_lists_lines_and_caps_the_list() -> None:
    report = _report([SkippedLine("f.csv", k, "malformed: not a number in 'x'", "x") for k in range(1, 26)])
    lines = str(report).splitlines()
    assert lines[0] == "25 lines skipped in f.csv: 25 malformed"
    assert lines[1] == "  f.csv, line 1: malformed: not a number in 'x'"
    assert len(lines) == 22 and lines[-1] == "  … and 5 more"
    one = _report([SkippedLine("f.csv", 4, "zero quaternion: zero quaternion", "0 0 0 0")])
    assert one.summary() == "1 line skipped in f.csv: 1 zero quaternion"


def test_options_are_checked(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text(EUROC_IMU[1] + "\n")
    with pytest.raises(ik.ParameterError, match=r"^on_bad_line: expected 'raise' or 'skip', got 'ignore'"):
        ik.io.read_euroc_imu(path, on_bad_line="ignore")  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^report: expected an imukit\.io\.ReadReport or None, got list"):
        ik.io.read_tum(path, report=[])  # type: ignore[arg-type]


def _report(skipped: list[SkippedLine]) -> ReadReport:
    report = ReadReport()
    report.skipped.extend(skipped)
    return report


def test_bytes_that_are_not_utf8_and_huge_stamps_are_bad_lines(tmp_path: Path) -> None:
    # A Latin-1 byte in one line, a 25-digit stamp in another: each is one bad line, not a crash.
    path = tmp_path / "data.csv"
    lines = [EUROC_IMU[1].encode(), b"1403715523917140000,0.1,\xb00.2,0.3,9.1,9.2,9.3", b"9" * 25 + b",1,2,3,4,5,6"]
    lines.append(b"9" * 5000 + b",1,2,3,4,5,6")  # past int()'s 4300-digit limit
    path.write_bytes(b"\n".join(lines) + b"\n")
    report = ReadReport()
    imu = ik.io.read_euroc_imu(path, on_bad_line="skip", report=report)
    assert len(imu) == 1
    assert [(s.line, s.kind) for s in report.skipped] == [(2, "malformed"), (3, "malformed"), (4, "malformed")]
    assert report.skipped[0].reason == "malformed: not a number in '1403715523917140000,0.1,\\udcb00.2,0.3,9.1,9.2,9.3'"
    assert report.skipped[1].reason.startswith("malformed: timestamp '9999999999999999999999999' is not an integer")


# Stamps out of order: every reader keeps the longest strictly increasing run of stamps (earliest lines
# among equally long ones), so one wild stamp costs its own line and nothing else.
STEP_NS = 5_000_000
T0_NS = 1_403_715_523_912_140_000


def _euroc_with_stamps(tmp_path: Path, steps: list[float]) -> Path:
    """Line k + 2 holds stamp T0 + steps[k] × 5 ms and gyro x = k + 1 (which samples survive is visible)."""
    path = tmp_path / "data.csv"
    rows = [f"{T0_NS + round(s * STEP_NS)},{k + 1}.0,0,0,0,0,9.81" for k, s in enumerate(steps)]
    path.write_text("\n".join([HEADER, *rows]) + "\n")
    return path


@pytest.mark.parametrize(
    ("steps", "skipped"),
    [
        # One stamp 10 s in the future: only it goes (the old rule kept it and dropped the 6 after it).
        ([0, 1, 2, 2000, 4, 5, 6, 7, 8, 9], [(5, "stamp out of order")]),
        ([2000, 1, 2, 3, 4], [(2, "stamp out of order")]),  # on the first line
        ([0, 1, 2, 3, 4000], []),  # on the last line it is the latest stamp: kept
        # One stamp 10 s in the past: only it goes, wherever it is.
        ([0, 1, 2, -2000, 4, 5, 6], [(5, "stamp going back")]),
        ([0, 1, 2, 3, -2000], [(6, "stamp going back")]),
        ([-2000, 1, 2, 3], []),  # on the first line it is the earliest stamp: kept
        # A run of equal stamps: the first is kept.
        ([0, 1, 1, 1, 1, 2], [(4, "duplicate stamp"), (5, "duplicate stamp"), (6, "duplicate stamp")]),
        # A block of 3 shifted back among 10 increasing stamps: the block (the shorter side) goes ...
        ([0, 1, 2, 3, 4, 5, 6, 7, 3.5, 4.5, 5.5, 8, 9], [(10, "stamp going back"), (11, "stamp going back"),
                                                        (12, "stamp going back")]),
        # ... and when the 2 lines before the jump back are the shorter side, they go instead.
        ([0, 1, 2, 10, 11, 3, 4, 5, 6, 7, 12], [(5, "stamp out of order"), (6, "stamp out of order")]),
        # Equally long sides: the earlier lines are kept.
        ([0, 1, 5, 6, 3, 4, 7], [(6, "stamp going back"), (7, "stamp going back")]),
    ],
)  # fmt: skip
def test_stamps_out_of_order_cost_only_the_fewest_lines(
    tmp_path: Path, steps: list[float], skipped: list[tuple[int, str]]
) -> None:
    path = _euroc_with_stamps(tmp_path, steps)
    report = ReadReport()
    imu = ik.io.read_euroc_imu(path, on_bad_line="skip", report=report)
    assert [(s.line, s.kind) for s in report.skipped] == skipped
    gone = {line - 2 for line, _ in skipped}
    kept = [k for k in range(len(steps)) if k not in gone]
    assert imu.gyro[:, 0].tolist() == [k + 1.0 for k in kept]
    assert imu.t_ns is not None and imu.t_ns.tolist() == [T0_NS + round(steps[k] * STEP_NS) for k in kept]


def test_out_of_order_messages_name_the_kept_stamp_they_clash_with(tmp_path: Path) -> None:
    path = _euroc_with_stamps(tmp_path, [0, 1, 2000, 3, 4, -2000, 5, 5])
    report = ReadReport()
    ik.io.read_euroc_imu(path, on_bad_line="skip", report=report)
    t = [T0_NS + s * STEP_NS for s in (0, 1, 2000, 3, 4, -2000, 5)]
    assert [s.reason for s in report.skipped] == [
        f"stamp out of order: time must increase strictly, but {t[2]} comes before {t[3]} (line 5)",
        f"stamp going back: time must increase strictly, but {t[5]} follows {t[4]} (line 6)",
        f"duplicate stamp: time must increase strictly, but {t[6]} follows {t[6]} (line 8)",
    ]
    # "raise" still stops at the first line whose stamp is not above the line before it.
    with pytest.raises(
        ik.io.FileFormatError,
        match=rf"^path: {re.escape(str(path))}, line 5: time must increase strictly, but {t[3]} follows {t[2]} "
        r"\(line 4\)$",
    ):
        ik.io.read_euroc_imu(path)


def _future_stamp_file(fmt: str, tmp_path: Path) -> tuple[Path, ik.ImuData | ik.Trajectory]:
    """Ten samples 5 ms apart, the 4th (line 5) stamped 10 s late, in format ``fmt``; what it reads as."""
    t = [1.0 + 0.005 * k for k in range(10)]
    t[3] += 10.0
    path = tmp_path / f"{fmt}.txt"
    if fmt == "tum":
        lines = ["# t x y z qx qy qz qw", *(f"{s!r} {k}.0 0 0 0 0 0 1" for k, s in enumerate(t))]
    elif fmt == "csv":
        lines = ["t,gx,gy,gz,ax,ay,az", *(f"{s!r},{k}.0,0,0,0,0,9.81" for k, s in enumerate(t))]
    else:  # GTSAM's dt is the step before the sample, printed from the stamps
        lines = ["Time dt accelX accelY accelZ omegaX omegaY omegaZ"]
        lines += [f"{s!r} {s - (t[k - 1] if k else 0.0)!r} 0 0 9.81 {k}.0 0 0" for k, s in enumerate(t)]
    path.write_text("\n".join(lines) + "\n")
    report = ReadReport()
    if fmt == "tum":
        data: ik.ImuData | ik.Trajectory = ik.io.read_tum(path, on_bad_line="skip", report=report)
    elif fmt == "csv":
        data = ik.io.read_imu_csv(
            path, time_column="t", gyro_columns=["gx", "gy", "gz"], accel_columns=["ax", "ay", "az"],
            on_bad_line="skip", report=report,
        )  # fmt: skip
    else:
        data = ik.io.read_gtsam_imu(path, on_bad_line="skip", report=report)
    assert [(s.line, s.kind) for s in report.skipped] == [(5, "stamp out of order")]
    return path, data


@pytest.mark.parametrize("fmt", ["tum", "csv", "gtsam"])
def test_every_text_reader_skips_only_the_future_stamp(fmt: str, tmp_path: Path) -> None:
    _, data = _future_stamp_file(fmt, tmp_path)
    values = data.position[:, 0] if isinstance(data, ik.Trajectory) else data.gyro[:, 0]
    assert values.tolist() == [0.0, 1.0, 2.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
    assert data.t.tolist() == [1.0 + 0.005 * k for k in (0, 1, 2, 4, 5, 6, 7, 8, 9)]


@requires_euroc
@pytest.mark.parametrize(("shift_ns", "kind"), [(10**10, "stamp out of order"), (-(10**10), "stamp going back")])
def test_real_euroc_excerpt_with_one_wild_stamp_loses_only_that_line(tmp_path: Path, shift_ns: int, kind: str) -> None:
    lines = IMU_CSV.read_text().splitlines()
    stamp, rest = lines[100].split(",", 1)
    lines[100] = f"{int(stamp) + shift_ns},{rest}"  # line 101, 10 s late or early
    path = tmp_path / "data.csv"
    path.write_text("\n".join(lines) + "\n")
    report = ReadReport()
    imu = ik.io.read_euroc_imu(path, on_bad_line="skip", report=report)
    assert [(s.line, s.kind) for s in report.skipped] == [(101, kind)]
    raw = np.loadtxt(IMU_CSV, delimiter=",", skiprows=1, dtype=str)  # an independent parse, line 101 removed
    raw = np.delete(raw, 99, axis=0)
    assert len(imu) == len(raw) == 7998
    assert imu.t_ns is not None and imu.t_ns.tolist() == [int(s) for s in raw[:, 0]]
    np.testing.assert_array_equal(imu.gyro, raw[:, 1:4].astype(np.float64))
    np.testing.assert_array_equal(imu.accel, raw[:, 4:7].astype(np.float64))


def test_excel_bom_and_crlf_read_as_without(tmp_path: Path) -> None:
    # Excel's "CSV UTF-8" starts with a byte order mark: the '#' header must stay a comment, not a bad line.
    plain = tmp_path / "plain.csv"
    plain.write_text("\n".join([*EUROC_IMU[:2], EUROC_IMU[5]]) + "\n")
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + plain.read_bytes().replace(b"\n", b"\r\n"))
    report = ReadReport()
    imu = ik.io.read_euroc_imu(bom, on_bad_line="skip", report=report)
    assert not report
    assert imu.t_ns is not None and imu.t_ns.tolist() == [1403715523912140000, 1403715523932140000]
    reference = ik.io.read_euroc_imu(plain)
    np.testing.assert_array_equal(imu.gyro, reference.gyro)
    np.testing.assert_array_equal(imu.accel, reference.accel)


def test_summary_names_every_kind_in_the_plural() -> None:
    kinds = {
        "malformed": "malformed", "wrong column count": "wrong column counts", "non-finite": "non-finite",
        "duplicate stamp": "duplicate stamps", "stamp going back": "stamps going back",
        "stamp out of order": "stamps out of order", "zero quaternion": "zero quaternions",
        "not a rotation": "not rotations", "unpaired": "unpaired", "missing field": "missing fields",
        "zero stamp": "zero stamps",
    }  # fmt: skip
    for kind, plural in kinds.items():
        two = _report([SkippedLine("b.bag", k, f"{kind}: detail", "") for k in (1, 2)])
        assert two.summary() == f"2 lines skipped in b.bag: 2 {plural}"
        one = _report([SkippedLine("b.bag", 1, f"{kind}: detail", "")])
        assert one.summary() == f"1 line skipped in b.bag: 1 {kind}"
    documented = inspect.getsource(SkippedLine)  # the reason field's docstring lists every kind
    assert [kind for kind in kinds if f"``{kind}``" not in documented] == []


def test_kept_stamps_are_the_earliest_longest_increasing_subsequence_by_brute_force(rng: np.random.Generator) -> None:
    # Against exhaustive search: combinations() yields index sets in lexicographic order, so the first
    # strictly increasing one of the greatest length is the earliest-lines longest subsequence.
    for _ in range(400):
        stamps = rng.integers(0, 5, size=int(rng.integers(1, 9))).tolist()
        expected = next(
            list(c)
            for size in range(len(stamps), 0, -1)
            for c in itertools.combinations(range(len(stamps)), size)
            if all(stamps[a] < stamps[b] for a, b in zip(c, c[1:]))
        )
        keep, out = in_order(stamps)
        assert keep == expected, stamps
        assert sorted(keep + [d.at for d in out]) == list(range(len(stamps)))
