"""A study: what varies across many runs, read from a YAML file and expanded into tasks.

    name: friction_robustness          # names the results file
    kind: mission                      # mission (simulate and judge) | suf (a prong design) | noop
    base:                              # the scenario every task starts from (optional)
      scenario_name: default           #   a name in scenario_file (default: the shipped file)
      scenario_text: "{simulation_duration: 60.0}"
    design: grid                       # grid: every combination of the factors; list: zipped
    timeout: 600                       # per task, wall time [s]
    factors:
      - {name: mission, values: [hit_target_front, open_door]}    # or `values: shipped`
      - {name: ground_friction, range: {start: 0.4, stop: 1.0, num: 4}}
      - {name: seed, field: random_seed, random: {low: 0, high: 1000, count: 3, seed: 7, integer: true}}
      - name: noise                    # a value may set several fields at once
        values:
          - {random_seed: 0, sensor_noise.enabled: false}
          - {random_seed: 1, sensor_noise.enabled: true}
        labels: [clean, noisy]         # optional: how the rows and the summary name the values
      - name: error                    # joint random draws of several fields (one value per draw)
        draw:
          count: 30                    # draws
          seed: 11                     # optional (default 0)
          fields:                      # field: distribution (optional size: a list of that many)
            model_error.payload_mass: {uniform: [0.0, 3.0]}
            model_error.motor_strength: {uniform: [0.6, 1.0], size: 4}
            model_error.foot_contact_stiffness: {log_uniform: [1880.0, 2.0e+5]}
            model_error.payload_offset: {ball: 0.05}      # a point uniform in a ball [x, y, z]
            random_seed: {integers: [0, 1000]}            # whole numbers, high excluded
            estimator: {choice: [kalman, ground_truth]}

A factor sets the scenario field `field` (default: its name; dotted for nested fields, e.g.
`sensor_noise.enabled`, `whole_body.stack`, `robot.prongs`), or, when a value is a mapping,
every field of that mapping. For `kind: suf` the fields are those of `SufDesign` (trunk height,
feet, prongs, method). Every task's settings are checked when the study is loaded, so a bad
study file stops before any task starts.

A `draw` factor draws every field of each of its values at random, each field from its own
generator (seeded by the draw's seed and the field's name, so adding a field leaves the others'
draws as they were). Its rows and summary name a draw by one number per field
(`draw_label`): the value itself, the smallest entry of a `size` draw (the weakest leg of
`model_error.motor_strength`), the distance from the centre of a `ball` draw (how far the
payload sits from the trunk centre), so that the summary can bin success against each field.
"""

import dataclasses
import hashlib
import itertools
import json
import math
import zlib
from pathlib import Path

import numpy as np
from pydrake.common.yaml import yaml_load

from pedi_drake.exceptions import ConfigError
from pedi_drake.mission.spec import load_mission, shipped_missions
from pedi_drake.scenario import Scenario, apply_scenario_text, load_scenario

KINDS = ("mission", "suf", "noop")
DESIGNS = ("grid", "list")
SUF_METHODS = ("exact", "single", "fibonacci", "affine", "quadratic")


class StudyError(ConfigError):
    """A study file that cannot be run (the message names the file and the field)."""


@dataclasses.dataclass
class SufDesign:
    """One prong design evaluation of a `kind: suf` study (see pedi_drake.suf.design)."""

    trunk_height: float = 0.27  # [m]
    feet_x: float = 0.19  # feet at (+-feet_x, +-feet_y) in the trunk frame [m]
    feet_y: float = 0.13  # [m]
    prongs: bool = True  # the two prong tips carry load besides the three stance feet
    method: str = "affine"  # SUF method (SUF_METHODS)
    optimise_feet: bool = False  # choose feet_x, feet_y that maximise the SUF at this height


@dataclasses.dataclass
class NoopTask:
    """A `kind: noop` task: it only waits, to measure an engine's own cost per task."""

    duration_s: float = 0.0  # how long the task sleeps [s]


@dataclasses.dataclass(frozen=True)
class Task:
    """One run of a study: its settings (field -> value) and a stable id for resuming."""

    study: str
    kind: str
    index: int
    factors: dict  # factor name -> the value it took (for the results' columns)
    settings: dict  # field -> value (scenario fields, or SufDesign fields)
    base: dict  # scenario_file, scenario_name, scenario_text
    timeout: float  # [s]

    @property
    def task_id(self) -> str:
        text = json.dumps([self.kind, self.base, self.settings], sort_keys=True, default=str)
        return hashlib.sha1(text.encode()).hexdigest()[:12]


@dataclasses.dataclass
class Study:
    name: str
    kind: str
    tasks: list[Task]
    factor_names: list[str]
    source: str  # the file it came from


# The distributions of a `draw` factor's fields and what each takes.
DISTRIBUTIONS = {
    "uniform": "[low, high]",
    "log_uniform": "[low, high], 0 < low (uniform in the logarithm)",
    "integers": "[low, high], whole numbers, high excluded",
    "choice": "a non-empty list of values, each as likely",
    "ball": "a radius > 0: a point [x, y, z] uniform in the ball of that radius about the origin",
}


def _draw_field(spec, count: int, rng: np.random.Generator, where: str) -> tuple[list, list]:
    """(values, labels) of `count` draws of one field from its distribution `spec`."""
    if not isinstance(spec, dict) or len(set(spec) & set(DISTRIBUTIONS)) != 1 or set(spec) - {*DISTRIBUTIONS, "size"}:
        raise StudyError(f"{where}: one of {sorted(DISTRIBUTIONS)} (and optionally size), got {spec!r}")
    (kind,) = set(spec) & set(DISTRIBUTIONS)
    args, size = spec[kind], spec.get("size")
    if size is not None and (kind in ("ball", "choice") or not (isinstance(size, int) and size >= 1)):
        raise StudyError(f"{where}.size: a whole number >= 1 for uniform, log_uniform or integers, got {size!r}")
    shape = (count,) if size is None else (count, size)
    if kind == "choice":
        if not isinstance(args, list) or not args:
            raise StudyError(f"{where}.choice: {DISTRIBUTIONS['choice']}, got {args!r}")
        values = [args[int(k)] for k in rng.integers(0, len(args), size=count)]
        return values, [v if isinstance(v, int | float | str | bool) else json.dumps(v) for v in values]
    if kind == "ball":
        if not (isinstance(args, int | float) and math.isfinite(args) and args > 0):
            raise StudyError(f"{where}.ball: {DISTRIBUTIONS['ball']}, got {args!r}")
        direction = rng.normal(size=(count, 3))
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        radius = args * rng.uniform(size=count) ** (1.0 / 3.0)
        points = direction * radius[:, None]
        return [[float(v) for v in p] for p in points], [float(r) for r in radius]
    ok = (
        isinstance(args, list) and len(args) == 2 and all(isinstance(v, int | float) and math.isfinite(v) for v in args)
    )
    if not ok or not args[0] < args[1] or (kind == "log_uniform" and args[0] <= 0):
        raise StudyError(f"{where}.{kind}: {DISTRIBUTIONS[kind]} with low < high, got {args!r}")
    low, high = args
    if kind == "integers":
        drawn = rng.integers(int(low), int(high), size=shape)
        convert = int
    elif kind == "log_uniform":
        drawn = np.exp(rng.uniform(math.log(low), math.log(high), size=shape))
        convert = float
    else:
        drawn = rng.uniform(low, high, size=shape)
        convert = float
    if size is None:
        values = [convert(v) for v in drawn]
        return values, list(values)
    return [[convert(v) for v in row] for row in drawn], [convert(min(row)) for row in drawn]


def _draw(spec, where: str) -> tuple[list[dict], list[dict]]:
    """(values, labels) of a `draw` factor: per draw, {field: value} and {field: label number}."""
    if not isinstance(spec, dict) or set(spec) - {"count", "seed", "fields"} or not {"count", "fields"} <= set(spec):
        raise StudyError(f"{where}: needs count and fields (optional seed), got {spec!r}")
    count, seed, fields = spec["count"], spec.get("seed", 0), spec["fields"]
    if not (isinstance(count, int) and not isinstance(count, bool) and count >= 1):
        raise StudyError(f"{where}.count: a whole number >= 1, got {count!r}")
    if not (isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        raise StudyError(f"{where}.seed: a whole number >= 0, got {seed!r}")
    if not isinstance(fields, dict) or not fields:
        raise StudyError(f"{where}.fields: a non-empty mapping of field: distribution")
    values, labels = [{} for _ in range(count)], [{} for _ in range(count)]
    for field, distribution in fields.items():
        # Each field's own stream: adding or reordering fields leaves the others' draws unchanged.
        rng = np.random.default_rng([seed, zlib.crc32(str(field).encode())])
        drawn, shown = _draw_field(distribution, count, rng, f"{where}.fields.{field}")
        for k in range(count):
            values[k][str(field)], labels[k][str(field)] = drawn[k], shown[k]
    return values, labels


def draw_label(label) -> bool:
    """Whether a row's factor value is a draw's label ({field: number or choice}, see `_draw`)."""
    return isinstance(label, dict) and bool(label) and all(isinstance(v, int | float | str) for v in label.values())


def _values(raw: dict, where: str, missions_ok: bool) -> tuple[list, list | None]:
    """(values, default labels) of a factor: the labels are the values, except for a draw."""
    if "draw" in raw and len([k for k in ("values", "range", "random") if k in raw]) == 0:
        return _draw(raw["draw"], f"{where}.draw")
    return _plain_values(raw, where, missions_ok), None


def _plain_values(raw: dict, where: str, missions_ok: bool) -> list:
    keys = [k for k in ("values", "range", "random", "draw") if k in raw]
    if len(keys) != 1:
        raise StudyError(f"{where}: give exactly one of values, range, random, draw (got {keys or 'none'})")
    key = keys[0]
    spec = raw[key]
    if key == "values":
        if spec == "shipped" and missions_ok:
            return shipped_missions()
        if not isinstance(spec, list) or not spec:
            raise StudyError(f"{where}.values: a non-empty list (or `shipped` for missions), got {spec!r}")
        return list(spec)
    if not isinstance(spec, dict):
        raise StudyError(f"{where}.{key}: a mapping, got {spec!r}")
    if key == "range":
        unknown = set(spec) - {"start", "stop", "num"}
        if unknown or not {"start", "stop", "num"} <= set(spec):
            raise StudyError(f"{where}.range: needs start, stop, num (and nothing else), got {sorted(spec)}")
        start, stop, num = spec["start"], spec["stop"], spec["num"]
        if not (isinstance(num, int) and num >= 1):
            raise StudyError(f"{where}.range.num: a whole number >= 1, got {num!r}")
        if not all(isinstance(v, int | float) and math.isfinite(v) for v in (start, stop)):
            raise StudyError(f"{where}.range: start and stop must be finite numbers")
        return [float(v) for v in np.linspace(start, stop, num)]
    unknown = set(spec) - {"low", "high", "count", "seed", "integer"}
    if unknown or not {"low", "high", "count"} <= set(spec):
        raise StudyError(f"{where}.random: needs low, high, count (optional seed, integer), got {sorted(spec)}")
    low, high, count = spec["low"], spec["high"], spec["count"]
    if not (isinstance(count, int) and count >= 1):
        raise StudyError(f"{where}.random.count: a whole number >= 1, got {count!r}")
    if not (isinstance(low, int | float) and isinstance(high, int | float) and low < high):
        raise StudyError(f"{where}.random: low < high, got low {low!r}, high {high!r} (an empty range)")
    rng = np.random.default_rng(spec.get("seed", 0))
    if spec.get("integer", False):
        return [int(v) for v in rng.integers(int(low), int(high), size=count)]
    return [float(v) for v in rng.uniform(low, high, size=count)]


def _nested(settings: dict) -> dict:
    """{'a.b': 1} -> {'a': {'b': 1}}."""
    out: dict = {}
    for path, value in settings.items():
        node = out
        parts = path.split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = value
    return out


def scenario_text_for(settings: dict) -> str:
    """The --scenario_text-style YAML mapping (as JSON, which YAML reads) of a task's scenario fields."""
    settings = dict(settings)
    if "mission" in settings and "controller" not in settings:
        settings["controller"] = "whole_body"
    return json.dumps(_nested(settings))


def _check_field(path: str, kind: str, where: str) -> None:
    schema = {"suf": SufDesign, "noop": NoopTask}.get(kind, Scenario)
    node = schema
    for part in path.split("."):
        fields = {f.name: f for f in dataclasses.fields(node)} if dataclasses.is_dataclass(node) else None
        if fields is None:
            return  # below a mapping-typed field (lcm_buses, ...): the loader checks it
        if part not in fields:
            raise StudyError(f"{where}: unknown field {path!r} for kind {kind} (known: {', '.join(sorted(fields))})")
        node = fields[part].type if dataclasses.is_dataclass(fields[part].type) else None
        if node is None:
            return


def scenario_for(task: Task) -> Scenario:
    """The scenario a `kind: mission` task runs (its mission gets room for every phase's timeout)."""
    base = task.base
    scenario = load_scenario(
        filename=base.get("scenario_file"),
        scenario_name=base.get("scenario_name", "default"),
        scenario_text=base.get("scenario_text", "{}"),
    )
    from_base = scenario.simulation_duration
    scenario = apply_scenario_text(scenario, scenario_text_for(task.settings))
    if scenario.mission and "simulation_duration" not in task.settings:
        scenario.simulation_duration = max(from_base, load_mission(scenario.mission).longest_duration())
    return scenario


def suf_design_for(task: Task) -> SufDesign:
    design = SufDesign(**{**dataclasses.asdict(SufDesign()), **task.settings})
    if design.method not in SUF_METHODS:
        raise StudyError(f"method: must be one of {SUF_METHODS}, got {design.method!r}")
    for name in ("trunk_height", "feet_x", "feet_y"):
        value = getattr(design, name)
        if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
            raise StudyError(f"{name}: a finite length > 0 m, got {value!r}")
    return design


def load_study(path: str | Path) -> Study:
    """Reads and checks a study file; raises StudyError naming the file and the field."""
    path = Path(path)
    if not path.is_file():
        raise StudyError(f"{path}: study file not found")
    try:
        raw = yaml_load(filename=str(path))
    except Exception as error:  # Drake's YAML parser raises RuntimeError with the line
        raise StudyError(f"{path}: not valid YAML: {error}") from None
    return study_from_dict(raw, str(path))


def study_from_dict(raw, where: str) -> Study:
    """`load_study` for an already-parsed mapping (`where` names it in errors)."""
    if not isinstance(raw, dict):
        raise StudyError(f"{where}: a study is a mapping")
    unknown = set(raw) - {"name", "kind", "base", "design", "factors", "timeout"}
    if unknown:
        raise StudyError(
            f"{where}: unknown field(s) {sorted(unknown)}; known: name, kind, base, design, factors, timeout"
        )
    name = raw.get("name", Path(where).stem)
    if not isinstance(name, str) or not name.replace("_", "").replace("-", "").isalnum():
        raise StudyError(f"{where}: name: letters, digits, - and _ only, got {name!r}")
    kind = raw.get("kind", "mission")
    if kind not in KINDS:
        raise StudyError(f"{where}: kind: must be one of {KINDS}, got {kind!r}")
    design = raw.get("design", "grid")
    if design not in DESIGNS:
        raise StudyError(f"{where}: design: must be one of {DESIGNS}, got {design!r}")
    timeout = raw.get("timeout", 900.0)
    if not (isinstance(timeout, int | float) and math.isfinite(timeout) and timeout > 0):
        raise StudyError(f"{where}: timeout: a finite number of seconds > 0, got {timeout!r}")
    base = raw.get("base", {}) or {}
    if not isinstance(base, dict) or set(base) - {"scenario_file", "scenario_name", "scenario_text"}:
        raise StudyError(f"{where}: base: a mapping of scenario_file, scenario_name, scenario_text")
    factors = raw.get("factors", [])
    if not isinstance(factors, list) or not factors:
        raise StudyError(f"{where}: factors: a non-empty list")
    names, columns = [], []
    for i, factor in enumerate(factors):
        at = f"{where}: factors[{i}]"
        if not isinstance(factor, dict) or "name" not in factor:
            raise StudyError(f"{at}: a mapping with a name")
        unknown = set(factor) - {"name", "field", "values", "range", "random", "draw", "labels"}
        if unknown:
            raise StudyError(f"{at}: unknown field(s) {sorted(unknown)}")
        if "draw" in factor and {"field", "labels"} & set(factor):
            raise StudyError(f"{at}: a draw names its fields and labels its values itself (no field, no labels)")
        fname = factor["name"]
        if fname in names:
            raise StudyError(f"{at}.name: duplicate factor {fname!r}")
        field = factor.get("field", fname)
        values, drawn_labels = _values(factor, at, missions_ok=(field == "mission"))
        labels = factor.get("labels", values if drawn_labels is None else drawn_labels)
        if "labels" in factor and (
            not isinstance(labels, list)
            or len(labels) != len(values)
            or not all(isinstance(label, str | int | float) for label in labels)
        ):
            raise StudyError(f"{at}.labels: a list of {len(values)} names (one per value), got {labels!r}")
        settings = []
        for k, value in enumerate(values):
            if isinstance(value, dict):
                for sub in value:
                    _check_field(str(sub), kind, f"{at}.values[{k}]")
                settings.append({str(f): v for f, v in value.items()})
            else:
                _check_field(field, kind, f"{at}.field")
                settings.append({field: value})
        names.append(fname)
        columns.append(list(zip(labels, settings, strict=True)))
    if design == "list" and len({len(c) for c in columns}) != 1:
        raise StudyError(f"{where}: design list: every factor needs the same number of values")
    combos = itertools.product(*columns) if design == "grid" else zip(*columns, strict=True)
    tasks = []
    for index, combo in enumerate(combos):
        settings, shown = {}, {}
        for fname, (value, setting) in zip(names, combo, strict=True):
            settings.update(setting)
            shown[fname] = value
        task = Task(name, kind, index, shown, settings, base, float(timeout))
        _check_task(task, f"{where}: task {index} ({shown})")
        tasks.append(task)
    return Study(name=name, kind=kind, tasks=tasks, factor_names=names, source=where)


def _check_task(task: Task, where: str) -> None:
    try:
        if task.kind == "mission":
            scenario_for(task)
        elif task.kind == "suf":
            suf_design_for(task)
        elif not all(isinstance(v, int | float) and math.isfinite(v) and v >= 0 for v in task.settings.values()):
            raise StudyError(f"duration_s: a finite number of seconds >= 0, got {task.settings}")
    except ConfigError as error:
        raise StudyError(f"{where}: {error}") from None
