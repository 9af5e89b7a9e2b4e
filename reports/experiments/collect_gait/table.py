"""collect_gait's table: each variant's dataset (frames, episodes at the goal) and its encoder's probes (R² of the
latent's linear probe on the variant's own held-out episodes), beside the pipeline's committed encoder.

    .venv/bin/python reports/experiments/collect_gait/table.py
"""

import json
from pathlib import Path

import pandas as pd

HERE = Path(__file__).resolve().parent
REPORTS = HERE.parents[1]
VARIANTS = {
    "pipeline (adopt_p138)": (REPORTS / "collect.json", REPORTS / "vae" / "metrics.json"),
    **{k: (HERE / f"collect_{k}.json", HERE / f"vae_{k}.json") for k in "ABDE"},
}

rows = []
for name, (collect_file, vae_file) in VARIANTS.items():
    collect, vae = json.loads(collect_file.read_text()), json.loads(vae_file.read_text())
    probe = vae["probe"]
    rows.append({"variant": name, "episodes": collect["episodes"], "frames": collect["frames"],
                 "goal": collect["terminations"].get("goal", 0), "val_episodes": vae["data"]["val_episodes"],
                 "rise_val_frames": int(probe["rise_val_frames"]),
                 "distance_r2": round(probe["rise_distance_r2"], 3), "height_r2": round(probe["rise_height_r2"], 3),
                 "qualifies": probe["rise_distance_r2"] >= 0.9 and probe["rise_height_r2"] >= 0.8})
print(pd.DataFrame(rows).set_index("variant").to_string())
