"""`splineimu scene` names its flags in the scene's own errors.

`splineimu scene static --t0-ns -1` said "`t0_ns` must be between 0 and ...": the scene's
argument, which the user never typed.
"""

from __future__ import annotations

import pytest

from splineimu import cli


def _error(capsys, argv):
    assert cli.main(argv) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    return err.strip()


@pytest.mark.parametrize("t0, got", [("-1", "-1"), (str(2**62), str(2**62))])
def test_scene_t0_out_of_range_names_the_flag(tmp_path, capsys, t0, got):
    out = tmp_path / "out"
    err = _error(capsys, ["scene", "static", "--duration", "1", "--t0-ns", t0, "-o", str(out)])
    assert err == f"splineimu scene: error: `--t0-ns` must be between 0 and {2**62 - 1}, got {got}"
    assert not out.exists()


def test_scene_t0_error_names_the_flag_with_tum_only(tmp_path, capsys):
    tum = tmp_path / "s.tum"
    err = _error(capsys, ["scene", "static", "--t0-ns", "-5", "--tum", str(tum)])
    assert "`--t0-ns` must be between 0 and" in err and "t0_ns" not in err
    assert not tum.exists()


def test_scene_t0_in_range_is_the_origin(tmp_path):
    tum = tmp_path / "s.tum"
    assert cli.main(["scene", "static", "--duration", "1", "--rate", "2", "--t0-ns", "1500000000", "--tum",
                     str(tum)]) == 0
    assert [ln.split()[0] for ln in tum.read_text().splitlines()[1:]] == ["1.500000000", "2.000000000",
                                                                         "2.500000000"]


def test_scene_file_t0_out_of_range_names_file_line_and_key(tmp_path, capsys):
    """A scene file's t0_ns: -1 was refused without its file or line, when the scene was made."""
    p = tmp_path / "s.yaml"
    p.write_text(f"motion:\n  scene: static\n  duration_s: 1\n  t0_ns: -1\noutput:\n  dir: {tmp_path / 'out'}\n")
    err = _error(capsys, ["run", str(p)])
    assert err == f"splineimu run: error: {p}:4: `motion.t0_ns` must be between 0 and {2**62 - 1}, got -1"
    assert not (tmp_path / "out").exists()


def test_scene_input_refuses_t0_out_of_the_scenes_range():
    from splineimu.api import SceneInput
    from splineimu.errors import ConfigError

    with pytest.raises(ConfigError, match=rf"^`t0_ns` must be between 0 and {2**62 - 1}, got -1$"):
        SceneInput("static", t0_ns=-1)
    assert SceneInput("static", t0_ns=2**62 - 1).t0_ns == 2**62 - 1
