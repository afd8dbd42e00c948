"""EuRoC MAV csv files: ground truth (``state_groundtruth_estimate0/data.csv``) and IMU
(``imu0/data.csv``).

EuRoC stamps are integer nanoseconds (~1.4e18, so they are never put through a float).
Its quaternions are written **w first** (``q_RS_w, q_RS_x, q_RS_y, q_RS_z``); the Python
API uses ``quat_xyzw`` and converts here, at the file boundary.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..validation import as_quat_xyzw, as_stamps_ns, as_vectors
from .poses import PoseTrack, track_from_table
from .tables import TableWriter, write_table
from .timestamps import _is_integer_text, read_table

if TYPE_CHECKING:
    from ..groundtruth import GroundTruth

__all__ = [
    "read_euroc_groundtruth",
    "read_groundtruth",
    "write_euroc_imu",
    "write_euroc_groundtruth",
    "EurocImuWriter",
    "EurocGroundtruthWriter",
    "EUROC_IMU_HEADER",
    "EUROC_GROUNDTRUTH_HEADER",
]

EUROC_IMU_COLUMNS = (
    "#timestamp [ns]",
    "w_RS_S_x [rad s^-1]",
    "w_RS_S_y [rad s^-1]",
    "w_RS_S_z [rad s^-1]",
    "a_RS_S_x [m s^-2]",
    "a_RS_S_y [m s^-2]",
    "a_RS_S_z [m s^-2]",
)
EUROC_IMU_HEADER = ",".join(EUROC_IMU_COLUMNS)

EUROC_GROUNDTRUTH_COLUMNS = (
    "#timestamp",
    " p_RS_R_x [m]",
    " p_RS_R_y [m]",
    " p_RS_R_z [m]",
    " q_RS_w []",
    " q_RS_x []",
    " q_RS_y []",
    " q_RS_z []",
    " v_RS_R_x [m s^-1]",
    " v_RS_R_y [m s^-1]",
    " v_RS_R_z [m s^-1]",
    " b_w_RS_S_x [rad s^-1]",
    " b_w_RS_S_y [rad s^-1]",
    " b_w_RS_S_z [rad s^-1]",
    " b_a_RS_S_x [m s^-2]",
    " b_a_RS_S_y [m s^-2]",
    " b_a_RS_S_z [m s^-2]",
)
#: EuRoC's own ground-truth header line, byte for byte.
EUROC_GROUNDTRUTH_HEADER = ",".join(EUROC_GROUNDTRUTH_COLUMNS)

_NAMES_17 = tuple(c.strip().split(" ")[0].lstrip("#") for c in EUROC_GROUNDTRUTH_COLUMNS)


def read_euroc_groundtruth(path, min_poses: int = 2, repeated_stamps: str = "error") -> PoseTrack:
    """Read EuRoC ground truth, or any EuRoC-like ``ns, p xyz, q wxyz`` csv.

    Parameters
    ----------
    path : str or os.PathLike
        Comma-separated file. Accepted layouts:

        - 17 columns, EuRoC's ``state_groundtruth_estimate0/data.csv``:
          ``timestamp [ns], p_RS_R xyz [m], q_RS wxyz, v_RS_R xyz [m/s],
          b_w_RS_S xyz [rad/s], b_a_RS_S xyz [m/s^2]``; velocity and biases are kept;
        - 8 columns (``ns, px, py, pz, qw, qx, qy, qz``); 9 to 16 columns keep the first
          8 and ignore the rest with a notice. The first data row decides between 8 and
          17 columns.

        Lines starting with ``#`` (EuRoC's header), blank lines and one non-numeric
        header line are skipped.
    min_poses : int, default 2
    repeated_stamps : {"error", "first"}, default "error"
        See :func:`splineimu.io.poses.clean_poses`.

    Returns
    -------
    PoseTrack
        ``velocity_world``, ``bias_gyro`` and ``bias_accel`` are set for 17 columns.

    Raises
    ------
    InputError
        As :func:`splineimu.io.tum.read_tum`; the stamp column must be integer
        nanoseconds (a decimal point is read as seconds, exactly).

    Examples
    --------
    Eight columns, quaternion w first:

    >>> import tempfile, pathlib
    >>> rows = ["#timestamp, p x, p y, p z, q w, q x, q y, q z",
    ...         "1403715524907143168,1,2,3,1,0,0,0", "1403715524912143104,1,2,3,0,0,0,1"]
    >>> csv = pathlib.Path(tempfile.mkdtemp(), "gt.csv")
    >>> _ = csv.write_text("\\n".join(rows) + "\\n")
    >>> gt = read_euroc_groundtruth(csv)
    >>> gt.t_ns[0], gt.quat_xyzw.tolist()
    (np.int64(1403715524907143168), [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 0.0]])
    """
    from ..errors import InputError
    from .sniff import add_format_hint

    try:
        return _read_groundtruth(path, min_poses, repeated_stamps)
    except InputError as exc:
        raise add_format_hint(exc, path, "euroc_gt") from None


def _read_groundtruth(path, min_poses, repeated_stamps):
    from .sniff import check_ns_spacing

    table = read_table(
        path, n_cols=8, column_names=_NAMES_17, sep=",", allow_header=True, wide_cols=17
    )
    notices = []
    unit = "ns" if all(_is_integer_text(s) for s in table.stamps) else "s"
    if unit == "s":
        notices.append("timestamps have a decimal point: read as seconds, not EuRoC's nanoseconds")
    v = table.values
    kw = {}
    if table.n_cols == 17:
        kw = dict(velocity_world=v[:, 7:10], bias_gyro=v[:, 10:13], bias_accel=v[:, 13:16])
    track = track_from_table(table, unit, v[:, [4, 5, 6, 3]], path=path, notices=notices, min_poses=min_poses,
                             repeated_stamps=repeated_stamps, **kw)
    if unit == "ns":
        check_ns_spacing(track.t_ns, path=path, advice="EuRoC stamps are integer nanoseconds: convert the column "
                         "(stamps with a decimal point are read as seconds)")
    return track


def _imu_table(t_ns, gyro, accel):
    """Stamps and the ``(N, 6)`` columns of EuRoC imu lines, checked (``-0.0`` becomes ``0``)."""
    t = as_stamps_ns(t_ns, increasing=False)
    n = t.shape[0]
    return t, np.hstack([as_vectors(gyro, "gyro", n), as_vectors(accel, "accel", n)]) + 0.0


def _groundtruth_table(t_ns, positions, quat_xyzw, velocity_world, bias_gyro, bias_accel):
    """Stamps and the ``(N, 16)`` columns of EuRoC ground-truth lines (quaternion w first), checked."""
    t = as_stamps_ns(t_ns, increasing=False)
    n = t.shape[0]
    q = as_quat_xyzw(quat_xyzw, "quat_xyzw", n)
    return t, np.hstack([
        as_vectors(positions, "positions", n),
        q[:, [3, 0, 1, 2]],
        as_vectors(velocity_world, "velocity_world", n),
        as_vectors(bias_gyro, "bias_gyro", n),
        as_vectors(bias_accel, "bias_accel", n),
    ])


def write_euroc_imu(path, t_ns, gyro, accel, header: str | None = None):
    """Write an EuRoC ``imu0/data.csv`` atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Target file (its folder must exist).
    t_ns : array_like of int, shape (N,)
        Sample stamps in ns.
    gyro : array_like, shape (N, 3)
        Body rate of the sensor frame, rad/s.
    accel : array_like, shape (N, 3)
        Specific force in the sensor frame, m/s^2.
    header : str, optional
        Header line without newline; default EuRoC's
        ``#timestamp [ns],w_RS_S_x [rad s^-1],...,a_RS_S_z [m s^-2]``.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InputError
        (a ``ValueError``) Shapes that do not match or non-finite values.

    See Also
    --------
    EurocImuWriter : the same lines, written piece by piece.

    Notes
    -----
    Values are written losslessly (see :func:`splineimu.io.tables.format_table`), a
    negative zero as ``0``; about 1.3 s of CPU per million rows (measured).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "data.csv"
    >>> _ = write_euroc_imu(p, [1403715523912140000], [[0.0, 0.1, -0.2]], [[0.0, 0.0, 9.81]])
    >>> print(p.read_text().splitlines()[1])
    1403715523912140000,0,0.1,-0.2,0,0,9.81
    """
    t, table = _imu_table(t_ns, gyro, accel)
    return write_table(path, t, table, EUROC_IMU_HEADER if header is None else header)


def write_euroc_groundtruth(path, t_ns, positions, quat_xyzw, velocity_world, bias_gyro, bias_accel):
    """Write an EuRoC ``state_groundtruth_estimate0/data.csv`` atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Target file (its folder must exist).
    t_ns : array_like of int, shape (N,)
    positions : array_like, shape (N, 3)
        ``p_RS_R``, m.
    quat_xyzw : array_like, shape (N, 4)
        ``q_RS``; written w first, as EuRoC does.
    velocity_world : array_like, shape (N, 3)
        ``v_RS_R``, m/s.
    bias_gyro : array_like, shape (N, 3)
        ``b_w_RS_S``, rad/s.
    bias_accel : array_like, shape (N, 3)
        ``b_a_RS_S``, m/s^2.

    Returns
    -------
    pathlib.Path

    See Also
    --------
    EurocGroundtruthWriter : the same lines, written piece by piece.

    Notes
    -----
    The header is EuRoC's, byte for byte (:data:`EUROC_GROUNDTRUTH_HEADER`). Values are
    lossless; about 4 s of CPU per million rows (16 values each, measured).

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "data.csv"
    >>> z = np.zeros((1, 3))
    >>> _ = write_euroc_groundtruth(p, [5], [[1.0, 2, 3]], [[0, 0, 0, 1.0]], z, z, z)
    >>> print(p.read_text().splitlines()[1])
    5,1,2,3,1,0,0,0,0,0,0,0,0,0,0,0,0
    """
    t, table = _groundtruth_table(t_ns, positions, quat_xyzw, velocity_world, bias_gyro, bias_accel)
    return write_table(path, t, table, EUROC_GROUNDTRUTH_HEADER)


class EurocImuWriter(TableWriter):
    """An EuRoC ``imu0/data.csv`` written piece by piece (see :func:`write_euroc_imu`).

    A new file (created exclusively, for an :class:`~splineimu.io.files.OutputFolder`'s
    temporary folder); pieces are formatted in background threads while the caller
    computes the next ones.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "data.csv"
    >>> with EurocImuWriter(p) as w:
    ...     w.write_samples([1000, 2000], [[0.0, 0.0, -0.0]] * 2, [[0.0, 0.0, 9.81]] * 2)
    >>> p.read_text().splitlines()[1:]
    ['1000,0,0,0,0,0,9.81', '2000,0,0,0,0,0,9.81']
    """

    def __init__(self, path, header: str | None = None):
        super().__init__(path, EUROC_IMU_HEADER if header is None else header)

    def write_samples(self, t_ns, gyro, accel) -> None:
        """Append samples (arguments as for :func:`write_euroc_imu`)."""
        self.write(*_imu_table(t_ns, gyro, accel))


class EurocGroundtruthWriter(TableWriter):
    """An EuRoC ``state_groundtruth_estimate0/data.csv`` written piece by piece (see
    :func:`write_euroc_groundtruth`, whose arguments :meth:`write_states` takes)."""

    def __init__(self, path):
        super().__init__(path, EUROC_GROUNDTRUTH_HEADER)

    def write_states(self, t_ns, positions, quat_xyzw, velocity_world, bias_gyro, bias_accel) -> None:
        """Append states (arguments as for :func:`write_euroc_groundtruth`)."""
        self.write(*_groundtruth_table(t_ns, positions, quat_xyzw, velocity_world, bias_gyro, bias_accel))


def read_groundtruth(path) -> GroundTruth:
    """Read an EuRoC 17-column ground truth (``state_groundtruth_estimate0/data.csv``) as a
    :class:`~splineimu.groundtruth.GroundTruth` (interpolated states).

    Raises
    ------
    InputError
        Unreadable file, or fewer columns (no velocity and biases).
    """
    from ..errors import InputError
    from ..groundtruth import GroundTruth
    from .sniff import add_format_hint

    try:
        track = _read_groundtruth(Path(path), 2, "error")
    except InputError as exc:  # the advice of read_euroc_groundtruth (use from-tum) is for synthesis
        raise add_format_hint(exc, path, "euroc_gt", use="this needs the 17-column EuRoC ground truth, "
                              "e.g. OUT/mav0/state_groundtruth_estimate0/data.csv") from None
    return GroundTruth.from_track(track)
