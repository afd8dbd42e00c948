"""IMU configuration files: Kalibr ``imu.yaml``, Kalibr / OpenVINS chains, EuRoC ``sensor.yaml``.

This module writes the files (:func:`write_imu_config`); the keys and their checks belong to
:class:`splineimu.imu.config.ImuConfig`, which reads them (:meth:`~splineimu.imu.config.ImuConfig.from_yaml`,
through :func:`read_imu_yaml`, re-exported here). Everything goes through the one YAML module,
:mod:`splineimu.io.yaml`: OpenCV's ``%YAML:1.0`` first line and ``!!opencv-matrix`` nodes are
read, Kalibr's ``1e-4`` is a float, and a file is replaced atomically.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..imu._config import read_imu_yaml
from ..imu._config_values import KALIBR_KEYS
from ..validation import as_rate_hz
from .yaml import float_text, write_yaml

__all__ = ["read_imu_yaml", "write_imu_yaml", "write_imu_config", "kalibr_imu_chain_text"]


def write_imu_yaml(path, data: dict, comment_lines=()) -> Path:
    """Write the mapping ``data`` of IMU keys (comment lines first) atomically, in a form that
    Kalibr (PyYAML) and OpenCV's ``FileStorage`` (OpenVINS, VINS-Fusion, Kimera) both read.

    The file starts with ``%YAML 1.1`` and ``---``, every float is written so that both read
    a float (``2.0e-05``, ``400.0``) and list items are indented under their key
    (:func:`~splineimu.io.yaml.dump_yaml` with ``opencv=True``).

    Parameters
    ----------
    path : str or os.PathLike
        Target file (replaced if it exists); missing folders are created.
    data : dict
        Keys and plain values (numbers, lists), as :meth:`ImuConfig.to_dict` gives them.
    comment_lines : sequence of str
        Lines starting with ``#``.

    Returns
    -------
    pathlib.Path
    """
    return write_yaml(path, data, comment_lines, opencv=True)


def write_imu_config(config, path, header: str | None = None, *, rostopic: str = "/imu0",
                     update_rate: float | None = None) -> Path:
    """Write the configuration as a Kalibr ``imu.yaml``, atomically (temporary file + rename).

    The file is Kalibr's ``imu.yaml`` (the four noise densities, ``rostopic``,
    ``update_rate``), followed by the other keys that are set (:meth:`ImuConfig.to_dict`). It starts
    with ``%YAML 1.1`` and ``---`` and writes every number as a float that PyYAML and
    OpenCV's ``FileStorage`` both read (``2.0e-05``, ``400.0``), so Kalibr, OpenVINS,
    VINS-Fusion and Kimera read it as it is; :meth:`ImuConfig.from_yaml` reads it back equal.

    Parameters
    ----------
    config : ImuConfig
    path : path-like
    header : str, optional
        Comment lines to put first (``#`` is added).
    rostopic : str, default "/imu0"
        The IMU's ROS topic (Kalibr requires the key).
    update_rate : float, optional
        The sample rate of the data this model describes [Hz], if it differs from
        :attr:`ImuConfig.update_rate` (e.g. the rate actually synthesized). Without either, the key
        is left out.

    Returns
    -------
    Path of the written file.

    Examples
    --------
    >>> import dataclasses, tempfile, pathlib
    >>> from splineimu.imu.config import ImuConfig
    >>> cfg = ImuConfig.from_dict({"gyroscope_noise_density": 2e-05, "update_rate": 200})
    >>> p = write_imu_config(cfg, pathlib.Path(tempfile.mkdtemp()) / "imu.yaml", update_rate=400)
    >>> print("\\n".join(line for line in p.read_text().splitlines() if not line.startswith("#")))
    %YAML 1.1
    ---
    gyroscope_noise_density: 2.0e-05
    gyroscope_random_walk: 0.0
    accelerometer_noise_density: 0.0
    accelerometer_random_walk: 0.0
    rostopic: /imu0
    update_rate: 400.0
    >>> ImuConfig.from_yaml(p) == dataclasses.replace(cfg, update_rate=400.0)
    True
    """
    lines = [
        "# IMU sensor model (splineimu). Continuous-time Kalibr units:",
        "#   *_noise_density: gyro rad/s/sqrt(Hz), accel m/s^2/sqrt(Hz)",
        "#   *_random_walk:   gyro rad/s^2/sqrt(Hz), accel m/s^3/sqrt(Hz)",
        "#   update_rate: Hz. Other keys: see `python -m pydoc splineimu.imu.config`.",
    ]
    if header:
        lines = ["# " + h if h else "#" for h in header.splitlines()] + lines
    rest = config.to_dict()
    data = {key: rest.pop(key) for key in KALIBR_KEYS}
    data["rostopic"] = str(rostopic)
    rate = rest.pop("update_rate", None) if update_rate is None else as_rate_hz(update_rate, "update_rate")
    rest.pop("update_rate", None)
    if rate is not None:
        data["update_rate"] = float(rate)
    data.update(rest)
    return write_imu_yaml(path, data, lines)


def _rows(key: str, M, indent: str) -> list[str]:
    return [f"{indent}{key}:"] + [f"{indent}  - [{', '.join(float_text(v + 0.0) for v in row)}]"
                                  for row in np.asarray(M, dtype=np.float64)]


def _number(value) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(float_text(v) for v in value) + "]"
    return float_text(value)


def kalibr_imu_chain_text(config, *, update_rate: float, rostopic: str = "/imu0", body_T_imu=None,
                          time_offset: float = 0.0, header=()) -> str:
    """The text of an OpenVINS ``kalibr_imu_chain.yaml`` for a sensor model.

    The form of OpenVINS's own ``config/*/kalibr_imu_chain.yaml``: ``%YAML:1.0``, then ``imu0:``
    with ``T_i_b`` (body points into the IMU frame: the inverse of ``body_T_imu``), the four
    Kalibr noise keys, ``rostopic``, ``time_offset``, ``update_rate``, ``model`` and the
    intrinsics ``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg`` of
    :func:`splineimu.imu.openvins.to_openvins` (identity / zero when the model has no scale,
    misalignment or g-sensitivity). :meth:`ImuConfig.from_yaml` reads it back to the same
    sensor model (its noise, per-axis densities as their largest axis, scale, misalignment and
    g-sensitivity; the other components are in ``imu.yaml``). OpenVINS reads one number per
    noise key: a density that differs between axes is written as its largest axis (the filter
    then never trusts the sensor more than it deserves), with the per-axis values in a comment;
    ``imu.yaml`` keeps them.

    Parameters
    ----------
    config : ImuConfig or None
        None: noise-free (densities zero).
    update_rate : float
        The rate of the data [Hz].
    rostopic : str
    body_T_imu : (4, 4) array_like, optional
        The IMU's pose in the body frame (identity when omitted).
    time_offset : float
    header : sequence of str
        Comment lines (``#`` is added).

    Examples
    --------
    >>> print(kalibr_imu_chain_text(None, update_rate=400).splitlines()[:9])
    ['%YAML:1.0', 'imu0:', '  T_i_b:', '    - [1.0, 0.0, 0.0, 0.0]', '    - [0.0, 1.0, 0.0, 0.0]', \
'    - [0.0, 0.0, 1.0, 0.0]', '    - [0.0, 0.0, 0.0, 1.0]', '  accelerometer_noise_density: 0.0', \
'  accelerometer_random_walk: 0.0']
    """
    from ..imu._config_values import compact
    from ..imu.openvins import to_openvins

    T_bi = np.eye(4) if body_T_imu is None else np.asarray(body_T_imu, dtype=np.float64)
    T_ib = np.eye(4)
    T_ib[:3, :3] = T_bi[:3, :3].T
    T_ib[:3, 3] = -T_bi[:3, :3].T @ T_bi[:3, 3]
    lines = ["%YAML:1.0", *("# " + h for h in header), "imu0:", *_rows("T_i_b", T_ib, "  ")]
    for key in ("accelerometer_noise_density", "accelerometer_random_walk",
                "gyroscope_noise_density", "gyroscope_random_walk"):
        value = compact(getattr(config, key)) if config is not None else 0.0
        if isinstance(value, list):
            # a comment inside the mapping upsets OpenCV's reader: it goes with the header
            lines.insert(1, f"# {key} per axis (x, y, z): {', '.join(float_text(v) for v in value)}; "
                            "OpenVINS reads one number: the largest is written")
            value = max(value)
        lines.append(f"  {key}: {_number(value)}")
    ov = to_openvins(config)
    lines += [f"  rostopic: {rostopic}", f"  time_offset: {float_text(time_offset)}",
              f"  update_rate: {float_text(update_rate)}", f"  model: \"{ov['model']}\""]
    for key in ("Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg"):
        lines += _rows(key, ov[key], "  ")
    return "\n".join(lines) + "\n"
