"""b before the single block's face and on its open ground per draw, pricezone and five04 (the same nine seeds).

    .venv/bin/python reports/experiments/pricezone/b_open.py
"""

import pandas as pd

rows = []
for sweep, cond in (("pricezone", "pricezone"), ("five04", "free80e04")):
    for s in (0, 1000, 2000, 1, 1001, 2001, 2, 1002, 2002):
        d = pd.read_csv(f"reports/sweeps/{sweep}/{cond}-seed{s}/eval/results.csv")
        sb = d[(d.controller == "policy") & (d.terrain == "single_block")]
        rows.append((sweep, s, round(sb.b_before_block.mean(), 3), round(sb.b_open.mean(), 3)))
t = pd.DataFrame(rows, columns=["sweep", "seed", "b_before", "b_open"]).pivot(index="seed", columns="sweep")
print(t.to_string())
print(t.mean().round(3).to_string())
