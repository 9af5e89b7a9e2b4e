"""Speed figures leave the metrics files (so `dvc metrics diff` shows results); the summary still shows them."""

import json

from hexpipe.speed import beside, machine, move_speed, read_with_speed, split


def test_split_moves_nested_and_top_level_keys_and_drops_emptied_sections():
    tree = {"time": {"steps_per_s": 3.0}, "train": {"loss": 1.0, "images_per_s": 9.0}, "step": 4, "wall": 2.0}
    results, speed = split(tree, ["time", "train/images_per_s", "wall", "missing", "nope/x"])
    assert results == {"train": {"loss": 1.0}, "step": 4}
    assert speed == {"time": {"steps_per_s": 3.0}, "train": {"images_per_s": 9.0}, "wall": 2.0}
    assert tree["time"] == {"steps_per_s": 3.0}  # the input is left alone
    results, speed = split({"a": {"b": 1}}, ["a/b"])
    assert results == {} and speed == {"a": {"b": 1}}


def test_move_and_read_back(tmp_path):
    metrics, speed = tmp_path / "metrics.json", tmp_path / "speed.json"
    metrics.write_text(json.dumps({"episode": {"success_rate": 0.5}, "time": {"steps_per_s": 100.0}, "step": 7}))
    move_speed(metrics, speed, ["time"])
    assert json.loads(metrics.read_text()) == {"episode": {"success_rate": 0.5}, "step": 7}
    assert json.loads(speed.read_text()) == {"time": {"steps_per_s": 100.0}}
    assert read_with_speed(metrics, speed)["time"]["steps_per_s"] == 100.0
    assert read_with_speed(tmp_path / "none.json", speed) is None
    assert beside(tmp_path / "collect.json") == tmp_path / "collect_speed.json"


def test_the_speed_file_names_the_machine(tmp_path):
    """Weights depend on the CPU's instruction set: the speed file says which one, the metrics file does not."""
    made_on = machine()
    assert made_on["torch_cpu_capability"] and made_on["torch_threads"] >= 1 and made_on["cpu"]
    metrics, speed = tmp_path / "metrics.json", tmp_path / "speed.json"
    metrics.write_text(json.dumps({"loss": 1.0, "time": {"steps_per_s": 5.0}}))
    move_speed(metrics, speed, ["time"], made_on)
    assert json.loads(speed.read_text())["machine"] == made_on and "machine" not in json.loads(metrics.read_text())


def test_summary_page_shows_speed_from_the_speed_files(tmp_path):
    from hexpipe.config import Params
    from hexpipe.summary import build_summary

    files = {"collect.json": {"episodes": 3}, "collect_speed.json": {"frames_per_s": 123.0},
             "vae/metrics.json": {"val": {"loss": 1.5}, "train": {"loss": 1.0},
                                  "probe": {"rise_distance_r2": 0.9, "profile_r2": {"band0": 0.25}}},
             "vae/speed.json": {"train": {"images_per_s": 456.0},
                                "machine": {"cpu": "Test CPU", "arch": "x86_64", "torch": "2.13.0",
                                            "torch_cpu_capability": "AVX512", "torch_threads": 2}},
             "ppo/metrics.json": {"step": 10, "episode": {"success_rate": 0.5}},
             "ppo/speed.json": {"time": {"train_steps_per_s": 789.0}}}
    for name, data in files.items():
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text(json.dumps(data))
    params = Params().model_copy(update={
        "vae": Params().vae.model_copy(update={"report_dir": str(tmp_path / "vae")}),
        "ppo": Params().ppo.model_copy(update={"report_dir": str(tmp_path / "ppo")}),
        "eval": Params().eval.model_copy(update={"report_dir": str(tmp_path / "eval")})})
    page = build_summary(params, tmp_path / "collect.json", tmp_path)
    for row in ("| frames_per_s | 123 |", "| train/images_per_s | 456 |", "| time/train_steps_per_s | 789 |",
                "| episode/success_rate | 0.5 |", "| val/loss | 1.5 |", "| probe/rise_distance_r2 | 0.9 |",
                "| probe/profile_r2/band0 | 0.25 |"):  # nested metrics get a row each
        assert row in page
    assert "Computed on Test CPU (x86_64, torch 2.13.0 dispatching AVX512 kernels, 2 threads)" in page
    assert page.count("Computed on") == 1  # the ppo speed file here names no machine (an older file): no line
