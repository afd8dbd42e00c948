"""Scene files with a ``vary:`` block: the job of every run of a Monte-Carlo batch.

::

    seed: 42
    vary:
      imu.model.gyroscope_noise_density: {normal: [1.8e-4, 2.0e-5]}
      imu.model.accelerometer_noise_density: {uniform: [1.0e-3, 3.0e-3]}
      imu.extrinsic.translation.0: {normal: [0.10, 0.005]}

Each key is a dotted path of the scene format (a number indexes a list); distributions are
described in :mod:`splineimu.batch.vary`. An IMU model given as a preset name or a file, and an
extrinsic given as a file (or not at all), are expanded to their keys so that one of them can
be varied. The block is checked when the file is read, before any work: each key is applied
with its nominal value and the job built, so that a key which is not part of the format, or a
value the format refuses, is an error naming the file, the line and the key.

Run ``k`` (:meth:`SceneFile.job`) takes the draws of ``k`` and its own seed, both from the
file's ``seed`` and ``k`` alone; without a run index the nominal values (mean, midpoint, first
choice) are used. ``splineimu run SCENE.yaml --run-index k`` and ``splineimu batch`` build their
jobs through this one method, so they write the same bytes.

Examples
--------
>>> import pathlib, tempfile
>>> f = pathlib.Path(tempfile.mkdtemp()) / "s.yaml"
>>> _ = f.write_text('''motion: {scene: static, duration_s: 1}
... imu: {rate_hz: 100, model: {gyroscope_noise_density: 0.01}}
... seed: 1
... output: {dir: out}
... vary:
...   imu.model.gyroscope_noise_density: {uniform: [0.01, 0.02]}
... ''')
>>> scene = SceneFile.read(f)
>>> scene.job().imu.imu_config.gyroscope_noise_density.tolist()
[0.015, 0.015, 0.015]
>>> scene.values(3) == scene.values(3), 0.01 <= scene.values(3)["imu.model.gyroscope_noise_density"] < 0.02
(True, True)
>>> _ = f.write_text(f.read_text().replace("gyroscope_noise_density: {", "gyro_noise: {"))
>>> SceneFile.read(f)
Traceback (most recent call last):
...
splineimu.errors.ConfigError: ...s.yaml:6: `vary.imu.model.gyro_noise`: `imu.model`: unknown IMU key `gyro_noise` ...
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path

from ..batch.vary import draws_for_run, nominal_values, parse_vary, run_seed, set_dotted
from ..errors import ConfigError, SplineImuError

#: Top-level keys a ``vary:`` block may not touch (each run has its own seed and folder).
NOT_VARIED = ("seed", "output", "vary")


def _resolve(base: Path, value: str) -> Path:
    q = Path(value).expanduser()
    return q if q.is_absolute() else base / q


def _expander(base: Path):
    """``expand(path, value)`` for :func:`~splineimu.batch.vary.set_dotted`: blocks given by name or file, or absent."""

    from .scenefile import KEYS

    def expand(path, value):
        if path == "imu.model" and (value is None or isinstance(value, str)):
            if value is None:
                return {}
            from ..imu.config import load_imu_config

            file = _resolve(base, value)
            return load_imu_config(str(file) if file.exists() or value.endswith((".yaml", ".yml")) else value).to_dict()
        if path == "imu.extrinsic" and (value is None or isinstance(value, str)):
            from ..imu.ideal import Extrinsic
            from ..lie import matrix_to_quat_xyzw

            e = Extrinsic() if value is None else Extrinsic.from_file(str(_resolve(base, value)))
            return {"translation": e.body_t_sensor.tolist(), "quat_xyzw": matrix_to_quat_xyzw(e.body_R_sensor).tolist()}
        if value is None and (path in ("motion.params", "imu.timing") or tuple(path.split(".")) in KEYS):
            return {}  # an absent optional block of the format
        if value is None and path == "imu.gravity":
            from .options import DEFAULT_GRAVITY

            return list(DEFAULT_GRAVITY)
        return None

    return expand


def _index(run_index) -> int:
    from ..validation import int_in_range

    return int_in_range(run_index, "run index", 0, 2**63 - 1)


@dataclass
class SceneFile:
    """A scene file read once, from which the job of any run is built.

    Attributes
    ----------
    doc : splineimu.io.yaml.YamlDoc
        The file as written (for the lines of its keys).
    base : pathlib.Path
        The folder relative paths in the file start from.
    vary : dict
        ``{dotted key: Distribution}`` of the ``vary:`` block (empty without one).
    data : dict
        The document with the varied blocks expanded and the nominal values set.
    """

    doc: object
    base: Path
    vary: dict
    data: dict

    @classmethod
    def read(cls, path) -> SceneFile:
        """Read and check a scene file and its ``vary:`` block (see the module docstring).

        Raises
        ------
        ConfigError
            As :func:`~splineimu.api.scenefile.load_scene_file`; for the ``vary:`` block with the
            line of the key at fault.
        """
        from ..io.yaml import YamlDoc, read_yaml
        from .scenefile import job_from_document

        doc = read_yaml(path, "scene file")
        base = Path(path).parent
        job_from_document(doc, base)  # the file without its draws: errors at their own lines
        vary = parse_vary(doc.data.get("vary"), doc)
        expand = _expander(base)
        data = copy.deepcopy(doc.data)
        for key, dist in vary.items():
            if key.split(".")[0] in NOT_VARIED:
                raise doc.error(f"`vary`: `{key}` cannot be varied (each run has its own seed and output folder)",
                                "vary", key)
            values = dist.params if dist.kind == "choice" else (dist.nominal(),)
            for value in values:
                trial = copy.deepcopy(doc.data)
                try:
                    set_dotted(trial, key, value, expand)
                    job_from_document(YamlDoc(trial, doc.name, doc.lines), base)
                except KeyError as exc:
                    raise doc.error(f"`vary`: `{key}` is not a key of the scene format (no `{exc.args[0]}`)",
                                    "vary", key) from None
                except SplineImuError as exc:
                    raise ConfigError(f"`vary.{key}`: {exc.problem}", path=doc.name, line=doc.line("vary", key),
                                      option=f"vary.{key}") from None
            set_dotted(data, key, dist.nominal(), expand)
        return cls(doc, base, vary, data)

    @property
    def seed(self) -> int | None:
        """The file's ``seed`` (the root of every run's draws and seed)."""
        return self.doc.data.get("seed")

    @property
    def varies_motion(self) -> bool:
        """Whether a varied key is under ``motion`` (then each run reads and fits its own motion)."""
        return any(key.split(".")[0] == "motion" for key in self.vary)

    def values(self, run_index: int | None = None) -> dict:
        """The varied values of run ``run_index`` (``{dotted key: value}``), or the nominal ones."""
        if run_index is None:
            return nominal_values(self.vary)
        return draws_for_run(self.vary, self._seed(), _index(run_index))

    def run_seed(self, run_index: int) -> int:
        """The seed of run ``run_index`` (it replaces the file's ``seed``)."""
        return run_seed(self._seed(), _index(run_index))

    def _seed(self) -> int:
        if self.seed is None:
            raise self.doc.error("runs of a batch need the scene's `seed` (their draws and seeds derive from it)")
        return int(self.seed)

    def job(self, run_index: int | None = None, out_dir=None):
        """The :class:`~splineimu.api.options.SynthesisJob` of run ``run_index`` (None: the nominal values).

        Parameters
        ----------
        run_index : int, optional
            With it the run's draws and seed are used and the file's ``output.tum`` is not
            written (it would be one file for all runs).
        out_dir : str or os.PathLike, optional
            The output folder instead of the file's ``output.dir``.

        Raises
        ------
        ConfigError
            A drawn value the format refuses (with the line of its key), a run index without
            the file's ``seed``.
        """
        import dataclasses

        from ..io.yaml import YamlDoc
        from .scenefile import job_from_document

        data = self.data
        if run_index is not None:
            data = copy.deepcopy(data)
            for key, value in self.values(run_index).items():
                set_dotted(data, key, value)
            data["seed"] = self.run_seed(run_index)
        job = job_from_document(YamlDoc(data, self.doc.name, self.doc.lines), self.base)
        if run_index is not None and job.output.tum is not None:
            job.output = dataclasses.replace(job.output, tum=None)
        if out_dir is not None:
            job.output = dataclasses.replace(job.output, dir=str(out_dir))
        return job


__all__ = ["SceneFile", "NOT_VARIED"]
