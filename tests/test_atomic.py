"""One atomic-write helper: an artifact appears whole or not at all."""

import json

import pytest

from hexpipe.atomic import atomic_dir, atomic_path, temp_path, write_json


def test_write_json_replaces_whole_file(tmp_path):
    out = tmp_path / "sub" / "m.json"
    write_json(out, {"b": 1, "a": 2})
    assert json.loads(out.read_text()) == {"a": 2, "b": 1}
    assert out.read_text().startswith('{\n  "a"')
    assert [p.name for p in out.parent.iterdir()] == ["m.json"]


def test_failed_write_keeps_old_file_and_leaves_no_temp(tmp_path):
    out = tmp_path / "m.json"
    write_json(out, {"v": 1})
    with pytest.raises(RuntimeError), atomic_path(out) as tmp:
        tmp.write_text("half")
        raise RuntimeError("interrupted")
    assert json.loads(out.read_text()) == {"v": 1}
    assert not temp_path(out).exists()


def test_temp_name_keeps_suffix_and_is_hidden(tmp_path):
    assert temp_path(tmp_path / "video.mp4").name == ".video.tmp.mp4"


def test_shared_writers_get_their_own_temp_names(tmp_path):
    out = tmp_path / "robot.urdf"
    with atomic_path(out, shared=True) as a, atomic_path(out, shared=True) as b:
        assert a != b and a.suffix == b.suffix == ".urdf" and a.name.startswith(".robot.tmp-")
        a.write_text("first")
        b.write_text("second")
    assert out.read_text() == "first"  # b is renamed in first (inner with), then a: each whole
    assert [p.name for p in tmp_path.iterdir()] == ["robot.urdf"]


def test_atomic_dir_replaces_the_folder_whole_or_not_at_all(tmp_path):
    out = tmp_path / "step-1"
    with atomic_dir(out) as tmp:
        (tmp / "model.zip").write_text("v1")
        (tmp / "extra").write_text("only in v1")
    with pytest.raises(RuntimeError), atomic_dir(out) as tmp:
        (tmp / "model.zip").write_text("half")
        raise RuntimeError("interrupted")
    assert sorted(p.name for p in out.iterdir()) == ["extra", "model.zip"]
    assert (out / "model.zip").read_text() == "v1"
    with atomic_dir(out) as tmp:
        (tmp / "model.zip").write_text("v2")
    assert [p.name for p in out.iterdir()] == ["model.zip"] and (out / "model.zip").read_text() == "v2"
    assert [p.name for p in tmp_path.iterdir()] == ["step-1"]  # no temp or old folder left
