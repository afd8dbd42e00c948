"""IMU configuration files: Kalibr ``imu.yaml``, Kalibr / OpenVINS chains, EuRoC ``sensor.yaml``.

This module reads and writes the files; the keys and their checks belong to
:class:`splineimu.imu.config.ImuConfig`, which calls it (:meth:`~splineimu.imu.config.ImuConfig.from_yaml`,
:meth:`~splineimu.imu.config.ImuConfig.to_yaml`). Everything goes through the one YAML module,
:mod:`splineimu.io.yaml`: OpenCV's ``%YAML:1.0`` first line and ``!!opencv-matrix`` nodes are
read, Kalibr's ``1e-4`` is a float, and a file is replaced atomically.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import ConfigError
from .yaml import YamlDoc, read_yaml, write_yaml

__all__ = ["read_imu_yaml", "write_imu_yaml"]


def read_imu_yaml(path) -> YamlDoc:
    """Read an IMU configuration file: a mapping of keys (flat, or a chain ``imu0: {...}``).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    YamlDoc
        ``data`` is the mapping; ``line(*keys)`` gives the line of each key.

    Raises
    ------
    ConfigError
        Missing or unreadable file, invalid YAML (with its line), or not a mapping.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "sensor.yaml"
    >>> _ = p.write_text("%YAML:1.0\\nrate_hz: 200\\ngyroscope_noise_density: 1.6968e-04\\n")
    >>> doc = read_imu_yaml(p)
    >>> doc.data["gyroscope_noise_density"], doc.line("rate_hz")
    (0.00016968, 2)
    """
    doc = read_yaml(path, "IMU configuration file")
    if not isinstance(doc.data, dict):
        raise ConfigError(f"expected a mapping of IMU parameters, got {type(doc.data).__name__}", path=doc.name)
    return doc


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
