"""Scene-file parameters with the wrong shape are errors at the file and line of their key.

A 3-vector parameter given as a scalar or a 2-list (or a scalar one as a list, or a negative
radius) passed the scene file's checks and was refused only when the scene was made, as
"scene 'circle' parameter `center_m`: expected 3 values, got shape (2,)" with no file and line;
the other parameter errors pointed at the `params:` line instead of the key's own.
"""

from __future__ import annotations

import pytest

from splineimu import cli
from splineimu.api import load_scene_file
from splineimu.errors import ConfigError

TEXT = "motion:\n  scene: circle\n  duration_s: 1\n  params:\n    speed_m_s: 1\n    {}\nimu:\n  rate_hz: 100\n" \
       "output:\n  dir: o\n"


@pytest.mark.parametrize("entry, problem", [
    ("center_m: 2.0", "scene 'circle' parameter `center_m`: expected 3 values, got shape ()"),
    ("center_m: [1, 2]", "scene 'circle' parameter `center_m`: expected 3 values, got shape (2,)"),
    ("center_m: '1,2,3,4'", "scene 'circle' parameter `center_m`: expected 3 values, got shape (4,)"),
    ("radius_m: [1, 2]", "scene 'circle' parameter `radius_m`: expected a scalar, got shape (2,)"),
    ("radius_m: -1", "scene 'circle' parameter `radius_m`: must be > 0, got -1.0"),
    ("center_m: [1, x, 3]", "`motion.params: center_m` must be a number, got 'x'"),
    ("radius_mm: 1", "`motion.params of scene circle` must be one of radius_m, speed_m_s, center_m, phase_rad, "
                     "got 'radius_mm'; did you mean 'radius_m'?"),
])
def test_parameter_errors_name_the_file_and_the_line_of_the_key(tmp_path, capsys, entry, problem):
    f = tmp_path / "s.yaml"
    f.write_text(TEXT.format(entry))
    with pytest.raises(ConfigError) as e:
        load_scene_file(f)
    assert str(e.value) == f"{f}:6: {problem}"
    assert cli.main(["run", str(f)]) == 1
    assert capsys.readouterr().err.strip() == f"splineimu run: error: {f}:6: {problem}"
    assert not (tmp_path / "o").exists()


def test_good_parameters_still_load_and_a_varied_shape_is_named(tmp_path):
    f = tmp_path / "s.yaml"
    f.write_text(TEXT.format("center_m: [1, 2, 3]"))
    assert load_scene_file(f).motion.params["center_m"] == [1.0, 2.0, 3.0]
    vary = "seed: 1\nvary:\n  motion.params.speed_m_s: {choice: [1, [1, 2]]}\n"
    f.write_text(TEXT.format("center_m: '1, 2, 3'") + vary)
    with pytest.raises(ConfigError) as e:
        load_scene_file(f)
    assert str(e.value) == (f"{f}:13: `vary.motion.params.speed_m_s`: scene 'circle' parameter `speed_m_s`: expected "
                            "a scalar, got shape (2,)")
