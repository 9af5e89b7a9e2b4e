"""Whether two sweep trials' evaluation episodes are identical, every field of every episode.

    python3 reports/experiments/fast_cycle/same_episodes.py A/result.json B/result.json
"""

import json
import sys
from pathlib import Path

if len(sys.argv) != 3 or not all(Path(p).is_file() for p in sys.argv[1:]):
    raise SystemExit("usage: same_episodes.py A/result.json B/result.json (two sweep trial records that exist)")
a, b = (json.loads(Path(p).read_text())["episodes"] for p in sys.argv[1:3])
print(f"{len(a)} and {len(b)} episodes; identical: {a == b}")
