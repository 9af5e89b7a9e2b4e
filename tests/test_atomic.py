"""One atomic-write helper: an artifact appears whole or not at all."""

import json

import pytest

from hexpipe.atomic import atomic_path, temp_path, write_json


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
