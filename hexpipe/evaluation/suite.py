"""The terrain suite: eval.terrains + eval.terrain_files + extra terrains, all validated before any episode runs."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from hexpipe.config import Params
from hexpipe.paths import safe_name
from hexpipe.sim.terrain import TerrainError, TerrainRecipe, load_terrain


@dataclass(frozen=True)
class Scenario:
    """One terrain of the suite: `source` as given (scenario name or YAML path), `stem` names its outputs."""

    source: str
    stem: str
    recipe: TerrainRecipe


def _stem(source: str) -> str:
    return safe_name(Path(source).stem, fallback="terrain")


def load_scenarios(sources: Iterable[str]) -> list[Scenario]:
    """Validate every source (TerrainError on the first bad one); repeats are dropped, clashing stems refused."""
    scenarios: dict[str, Scenario] = {}
    for source in dict.fromkeys(str(s) for s in sources):  # keeps order, drops repeats
        scenario = Scenario(source, _stem(source), load_terrain(source))
        if (other := scenarios.get(scenario.stem)) is not None:
            raise TerrainError(
                f"terrains '{other.source}' and '{source}' would share the output name '{scenario.stem}'; rename one"
            )
        scenarios[scenario.stem] = scenario
    if not scenarios:
        raise TerrainError("no terrains to evaluate: eval.terrains and eval.terrain_files are empty")
    return list(scenarios.values())


def evaluation_suite(params: Params, extra: Iterable[str] = ()) -> list[Scenario]:
    """The terrains every controller is evaluated on."""
    return load_scenarios([*params.eval.terrains, *params.eval.terrain_files, *extra])


def training_suite(params: Params) -> list[Scenario]:
    """The policy's training terrains (ppo.train_terrains), on which the best fixed gait is chosen."""
    return load_scenarios(params.ppo.train_terrains)
