"""Load an unmodified SimMeR ``config.py`` (v1.0 and v1.1 forms) as a SimMeR 2 configuration.

The file runs as Python with stand-ins for what it imports (:mod:`simmer.compat.standins`), and
its globals are mapped to the native schema, then validated like a TOML file, so every message
applies, with the config.py line where the setting is written:

* top-level names that are SimMeR settings (BEHAVIOUR §8) are kept; the derived maze sizes
  (``maze_dim_x``, ``maze_dim_y``) and helper variables (``m0_info``...) are ignored;
* which original the file was written for decides what the two-port scheme and the serial port
  speak, unless the file says (``protocol``, ``reply_bytes``): ``frame_start``/``frame_end``
  mean SimMeR v1.2 (framed text), ``maze_dim_x`` without them v1.1 (4-byte floats), neither
  v1.0 (8-byte doubles) (BEHAVIOUR §6.1); commands are read the originals' way
  (``lenient_commands``, BEHAVIOUR §6.2);
* the keys of ``motors``, ``drives`` and ``sensors`` are the device ids; an info dictionary's
  ``'id'`` that disagrees is reported in the log and otherwise ignored;
* ``pm.Vector2`` becomes ``[x, y]``, tuples become lists, a drive's list of motor objects
  becomes their ids;
* keys that meant nothing are dropped: a drive's ``position`` and ``rotation`` (its direction is
  its velocity), ``velocity = [0, 0]`` beside an ``ang_velocity`` and ``ang_velocity = 0``
  beside a ``velocity``, ``outline_thickness`` (every outline is drawn at one width), and an
  infrared sensor's ``bias`` (SimMeR 2's infrared has none);
* an object of the user's own class (``from devices.template import Template``) in ``sensors``
  becomes ``type = "simmer_device"`` (:mod:`simmer.compat.template`);
* a setting written in a whole-line comment, in an info dictionary (``# 'error': 0.02,``) or
  at the top level (``# simulate_list = ['u0']``), is kept in :attr:`SimmerPy.commented_out`:
  the lab switches noise on by uncommenting such lines, so ``simmer convert`` carries them over.
"""

from __future__ import annotations

import ast
import difflib
import io
import logging
import os
import tokenize
import traceback
import types
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from simmer.compat import template
from simmer.compat.standins import StandInDevice, StandIns, Vector2, builtin_kind, captured_info
from simmer.config.models import DEVICE_GROUPS, Settings, SimConfig
from simmer.config.validate import DEFAULT_KIND, config_from_dict, oversize_walls
from simmer.errors import ConfigError, ConfigIssue, describe_exception

log = logging.getLogger(__name__)

IGNORED_SETTINGS = frozenset({"maze_dim_x", "maze_dim_y"})
"""SimMeR settings that SimMeR 2 derives itself (the maze's size in inches)."""


@dataclass(frozen=True)
class CommentedOut:
    """A setting written in a whole-line comment: ``table`` is the device's path
    (``drives.w0``), or "" for a top-level setting; ``comment`` is one written after it."""

    table: str
    key: str
    value: Any
    line: int
    comment: str | None = None


@dataclass
class SimmerPy:
    """A SimMeR ``config.py`` read into native data, with where each key is written.

    ``spans`` maps a native key path (``robot_width``, ``sensors.u0``, ``sensors.u0.height``)
    to its first and last line; ``comments`` maps a line to the comment written after code on
    it, ``alone`` a line to a whole-line comment.
    """

    path: Path
    data: dict[str, Any]
    spans: dict[str, tuple[int, int]] = field(default_factory=dict)
    comments: dict[int, str] = field(default_factory=dict)
    alone: dict[int, str] = field(default_factory=dict)
    commented_out: list[CommentedOut] = field(default_factory=list)
    """Settings commented out, in the order of the file (see the module doc)."""
    version: str = ""
    """The original release the file was written for: ``v1.0``, ``v1.1`` or ``v1.2``."""
    origin: str = ""
    """What that means for a run, said at start (see :func:`original_protocol`)."""

    def line_of(self, key: str) -> int | None:
        """The line of ``key`` or of its nearest written parent (``a.b[2].c`` -> ``a.b``...)."""
        key = key.split("[", 1)[0]
        while key:
            if key in self.spans:
                return self.spans[key][0]
            key = key.rpartition(".")[0]
        return None

    def comment_for(self, key: str) -> str | None:
        """The comments written on the lines of ``key``, joined; None if there are none."""
        if key not in self.spans:
            return None
        first, last = self.spans[key]
        found = [self.comments[n] for n in range(first, last + 1) if n in self.comments]
        return " ".join(found) or None


def load_simmer_py(path: str | Path) -> SimConfig:
    """Load a SimMeR ``config.py``; raise :class:`ConfigError` naming file and line on problems.

    Checked as an original (BEHAVIOUR §6.3): what the original ran but a TOML file may not have
    is in the result's ``warnings``, with lines like errors.
    """
    source = read_simmer_py(path)

    def placed(issue: ConfigIssue) -> ConfigIssue:
        return replace(issue, line=issue.line or source.line_of(issue.key))

    try:
        config = config_from_dict(source.data, str(source.path), source.path.parent, original=True)
    except ConfigError as exc:
        raise ConfigError(exc.source, [placed(issue) for issue in exc.issues]) from None
    # in the order of the file
    warnings = tuple(sorted(map(placed, config.warnings), key=lambda issue: issue.line or 0))
    return replace(config, warnings=warnings, origin=source.origin)


def read_simmer_py(path: str | Path) -> SimmerPy:
    """Run a SimMeR ``config.py`` with stand-ins and map its globals to native data."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(path, [ConfigIssue("", f"cannot read the file: {exc}")]) from None
    try:
        code = compile(text, str(path), "exec", dont_inherit=True)
        tree = ast.parse(text, str(path))
    except SyntaxError as exc:
        raise ConfigError(path, [_syntax_issue(exc, text)]) from None
    after_code, alone = _comments(text)
    result = SimmerPy(path, {}, comments=after_code, alone=alone)
    namespace = _run(path, code)
    _Mapper(result, namespace, tree).map()
    return result


# ----------------------------------------------------------------------------- errors


def _syntax_issue(exc: SyntaxError, text: str) -> ConfigIssue:
    line = exc.lineno
    lines = text.splitlines()
    shown = lines[line - 1].strip() if line and 0 < line <= len(lines) else ""
    if "forgot a comma" in (exc.msg or ""):
        following = f" and the entry on line {exc.end_lineno}" if exc.end_lineno else ""
        message = (
            f"a comma is missing between `{shown}`{following}. When you comment a line out or "
            "back in, make sure every entry of a dictionary or list is followed by a comma "
            "(a comma after the last one is fine too)"
        )
    else:
        message = (
            f"Python cannot read this line ({exc.msg}): `{shown}`. Check brackets, quotes and "
            "commas here and on the line above"
        )
    return ConfigIssue("", message, line)


def _run(path: Path, code: types.CodeType) -> dict[str, Any]:
    """Execute the configuration with the stand-ins in place and return its globals."""
    config = types.ModuleType("config", "The SimMeR configuration being loaded.")
    config.__file__ = str(path)
    device_dirs = [
        d for d in (path.parent / "devices", path.parent.parent / "devices") if d.is_dir()
    ]
    stand_ins = StandIns(path.parent, device_dirs, config)
    try:
        with stand_ins:
            exec(code, config.__dict__)
    except (Exception, SystemExit) as exc:
        raise ConfigError(path, [_exception_issue(exc, path)]) from None
    finally:
        for module in stand_ins.user_modules.values():
            template.remember_module(module, config)
    return config.__dict__


def _exception_issue(exc: Exception | SystemExit, path: Path) -> ConfigIssue:
    frames = [f for f in _frames(exc) if Path(f[0]).resolve() == path.resolve()]
    line = frames[-1][1] if frames else None
    what = describe_exception(exc, path.parent)
    if isinstance(exc, ModuleNotFoundError):
        hint = (
            "while loading a SimMeR config.py, SimMeR 2 provides pygame.math and the devices "
            "modules (motors, drive, ultrasonic, gyroscope, compass, infrared, device) and your "
            "own devices/<name>.py files; install any other module, or remove the import"
        )
    elif isinstance(exc, KeyError):
        hint = (
            "a name used in [...] does not exist; a drive's 'motors' may only list motors "
            "defined in the motors dictionary above it, e.g. motors['m0']"
        )
    elif isinstance(exc, NameError):
        hint = "check the spelling, and that the name is defined or imported above this line"
    else:
        hint = "fix the line named here, then run `simmer check` again"
    return ConfigIssue("", f"running the configuration failed: {what}; {hint}", line)


def _frames(exc: BaseException) -> list[tuple[str, int]]:
    return [(f.filename, f.lineno or 0) for f in traceback.extract_tb(exc.__traceback__)]


# ----------------------------------------------------------------------------- source positions


def _comments(text: str) -> tuple[dict[int, str], dict[int, str]]:
    """Comments by line number, without their ``#``: those written after code on a line, and
    whole-line ones."""
    after_code: dict[int, str] = {}
    alone: dict[int, str] = {}
    code_lines: set[int] = set()
    skip = (tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT)
    for token in tokenize.generate_tokens(io.StringIO(text).readline):
        if token.type == tokenize.COMMENT:
            found = after_code if token.start[0] in code_lines else alone
            found[token.start[0]] = token.string[1:].strip()
        elif token.type not in skip:
            code_lines.update(range(token.start[0], token.end[0] + 1))
    return after_code, alone


def _commented_setting(text: str, *, entry: bool) -> tuple[str, Any, str | None] | None:
    """A whole-line comment read as a setting: ``'error': 0.02,  # noisy`` (an info dictionary
    ``entry``) or ``simulate_list = ['u0']`` -> key, value, the comment after it; None if the
    comment is prose, or code that is not a literal setting."""
    try:
        if entry:
            node = ast.parse("{\n" + text + "\n}", mode="eval").body
            if not (isinstance(node, ast.Dict) and len(node.keys) == 1):
                return None
            key, value = node.keys[0], node.values[0]
            name = key.value if isinstance(key, ast.Constant) else None
        else:
            body = ast.parse(text).body
            statement = body[0] if len(body) == 1 else None
            if not (isinstance(statement, ast.Assign) and len(statement.targets) == 1):
                return None
            target, value = statement.targets[0], statement.value
            name = target.id if isinstance(target, ast.Name) else None
        if not isinstance(name, str):
            return None
        literal = _plain(ast.literal_eval(value))
    except (SyntaxError, ValueError, TypeError, MemoryError, RecursionError):
        return None
    tokens = tokenize.generate_tokens(io.StringIO(text).readline)
    comment = next((t.string[1:].strip() for t in tokens if t.type == tokenize.COMMENT), None)
    return name, literal, comment or None


def _assignments(tree: ast.Module) -> dict[str, tuple[ast.stmt, ast.expr]]:
    """The last top-level assignment of each simple name: ``name = value``."""
    found: dict[str, tuple[ast.stmt, ast.expr]] = {}
    for node in tree.body:
        if isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name):
                    found[target.id] = (node, node.value)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.value:
            found[node.target.id] = (node, node.value)
    return found


def _span(node: ast.AST, start: ast.AST | None = None) -> tuple[int, int]:
    first = getattr(start or node, "lineno", 0)
    return first, getattr(node, "end_lineno", None) or first


# ----------------------------------------------------------------------------- mapping


class _Mapper:
    """Turns a configuration's globals into native data, recording lines as it goes."""

    def __init__(self, result: SimmerPy, namespace: dict[str, Any], tree: ast.Module) -> None:
        self.result = result
        self.namespace = namespace
        self.statements = _assignments(tree)
        self.assigned = {name: value for name, (_, value) in self.statements.items()}
        self.issues: list[ConfigIssue] = []
        self.motor_ids: dict[int, str] = {}
        self.top_level = [_span(node) for node in tree.body]
        self.info_dicts: dict[str, ast.Dict] = {}  # device path -> its info dictionary literal

    def map(self) -> None:
        data = self.result.data
        for name, (statement, _) in self.statements.items():
            self.result.spans[name] = _span(statement)
        oversize = oversize_walls(self.namespace.get("walls"))
        if oversize is not None:  # before copying it: a huge matrix took minutes to copy
            issue = replace(oversize, line=self.result.line_of("walls"))
            raise ConfigError(self.result.path, [issue])
        for name in Settings.model_fields:
            if name in self.namespace:
                data[name] = _plain(self.namespace[name])
        self.result.version, self.result.origin = original_protocol(self.namespace, data)
        self._warn_unknown_names()
        last_line = max((n.lineno for n in self.assigned.values()), default=1)
        for group in DEVICE_GROUPS:
            table = self.namespace.get(group)
            if table is None:
                self.issues.append(self._missing_group(group, last_line))
            elif not isinstance(table, dict):
                self.issues.append(
                    ConfigIssue(
                        group,
                        f"must be a dictionary like {group} = {{'xx': ...}}, "
                        f"not {type(table).__name__}",
                        self.result.line_of(group),
                    )
                )
            else:
                data[group] = self._group(group, table)
        if self.issues:
            raise ConfigError(self.result.path, self.issues)
        self._commented_out()

    def _missing_group(self, group: str, last_line: int) -> ConfigIssue:
        before = {"motors": None, "drives": "motors", "sensors": "drives"}[group]
        line = self.result.spans[before][1] + 1 if before in self.result.spans else last_line
        return ConfigIssue(
            group,
            f"is missing: a SimMeR configuration must define motors, drives and sensors "
            f"dictionaries; add `{group} = {{}}` (empty if the robot has none) near line {line}",
            line,
        )

    def _warn_unknown_names(self) -> None:
        settings = list(Settings.model_fields)
        for name, value in self.namespace.items():
            if name in settings or name in IGNORED_SETTINGS or name in DEVICE_GROUPS:
                continue
            if name.startswith("_") or isinstance(value, types.ModuleType | type | dict):
                continue
            close = difflib.get_close_matches(name, settings, n=1, cutoff=0.8)
            if close:
                log.warning(
                    "%s:%s: %r is not a SimMeR setting (did you mean %r?); ignored",
                    self.result.path,
                    self.result.line_of(name),
                    name,
                    close[0],
                )

    def _group(self, group: str, table: dict[Any, Any]) -> dict[str, Any]:
        if group == DEVICE_GROUPS[0]:
            self._name_motors()
        entries = _dict_entries(self.assigned.get(group))
        out: dict[str, Any] = {}
        for key, device in table.items():
            device_id = str(key)
            path = f"{group}.{device_id}"
            entry = entries.get(device_id)
            if entry is not None:
                self.result.spans[path] = _span(entry[1], entry[0])
                self._info_spans(path, entry[1])
            native = self._device(group, device_id, device)
            if native is not None:
                out[device_id] = native
        return out

    def _name_motors(self) -> None:
        """Know every motor object by its id before any drive lists motors: those in
        ``motors`` first, then any listed only elsewhere (the original ran a motor among the
        sensors; the loader moves it)."""
        for group in DEVICE_GROUPS:
            table = self.namespace.get(group)
            if isinstance(table, dict):
                for key, device in table.items():
                    if isinstance(device, StandInDevice) and builtin_kind(device) == "motor":
                        self.motor_ids.setdefault(id(device), str(key))

    def _info_spans(self, path: str, call: ast.expr) -> None:
        """Record the lines of each key of the info dictionary a device was built from."""
        if not (isinstance(call, ast.Call) and call.args):
            return
        arg = call.args[0]
        literal = self.assigned.get(arg.id) if isinstance(arg, ast.Name) else arg
        if isinstance(literal, ast.Dict):
            self.info_dicts[path] = literal
        for key, (key_node, value) in _dict_entries(literal).items():
            self.result.spans[f"{path}.{key}"] = _span(value, key_node)
            for sub, (sub_node, sub_value) in _dict_entries(value).items():
                self.result.spans[f"{path}.{key}.{sub}"] = _span(sub_value, sub_node)

    def _device(self, group: str, device_id: str, device: object) -> dict[str, Any] | None:
        path = f"{group}.{device_id}"
        line = self.result.line_of(path)
        if not isinstance(device, StandInDevice):
            self.issues.append(
                ConfigIssue(
                    path,
                    f"must be a device such as MotorSimple(m0_info) or Ultrasonic(u0_info), "
                    f"not {type(device).__name__}",
                    line,
                )
            )
            return None
        info = captured_info(device)
        given_id = info.pop("id", device_id)
        if given_id != device_id:
            log.warning(
                "%s:%s: %s['%s'] has 'id': %r; using the dictionary key %r as its id",
                self.result.path,
                self.result.line_of(f"{path}.id") or line,
                group,
                device_id,
                given_id,
                device_id,
            )
        native = {k: self._value(v) for k, v in info.items()}
        kind = builtin_kind(device)
        if kind is None:
            return self._user_device(group, path, device, native)
        if kind != DEFAULT_KIND.get(group):  # a motor among the sensors says so
            native = {"type": kind, **native}
        self._drop_meaningless(path, kind, native)
        return native

    def _user_device(
        self, group: str, path: str, device: StandInDevice, native: dict[str, Any]
    ) -> dict[str, Any] | None:
        cls = type(device)
        line = self.result.line_of(path)
        d_type = getattr(device, "d_type", "")
        if group != "sensors" or d_type in ("motor", "drive"):
            self.issues.append(
                ConfigIssue(
                    path,
                    f"{cls.__name__} is a {d_type or group[:-1]} of your own; SimMeR 2 runs "
                    "SimMeR-style device classes only as sensors (in the sensors dictionary, "
                    "d_type 'sensor'). Move it to sensors if it only measures; a device that "
                    "moves the robot must use Drive and MotorSimple",
                    line,
                )
            )
            return None
        module = _user_module_path(cls, self.result.path.parent)
        if module is None:
            self.issues.append(
                ConfigIssue(
                    path,
                    f"{cls.__name__} is not defined in a devices/<name>.py file next to the "
                    "configuration; move the class into one, as SimMeR's template suggests",
                    line,
                )
            )
            return None
        return {"type": template.KIND, "module": module, "class_name": cls.__name__, **native}

    def _commented_out(self) -> None:
        """Find the settings written in whole-line comments (see the module doc)."""
        spans = self.result.spans
        for line, text in sorted(self.result.alone.items()):
            table = next(
                (
                    path
                    for path, literal in self.info_dicts.items()
                    if literal.lineno < line < (literal.end_lineno or 0)
                ),
                None,
            )
            if table is not None:
                inside_a_value = any(
                    key.startswith(f"{table}.") and first <= line <= last
                    for key, (first, last) in spans.items()
                )
                found = None if inside_a_value else _commented_setting(text, entry=True)
                if found is None or not self._kept(table, found[0], found[1]):
                    continue
            elif any(first <= line <= last for first, last in self.top_level):
                continue
            else:
                table = ""
                found = _commented_setting(text, entry=False)
                if found is None or found[0] not in Settings.model_fields:
                    continue
            key, value, comment = found
            self.result.commented_out.append(CommentedOut(table, key, value, line, comment))

    def _kept(self, path: str, key: str, value: Any) -> bool:
        """Whether a commented-out entry of a device's info dictionary means something to
        SimMeR 2 (not its ``id``, nor a key the mapping drops)."""
        group, _, device_id = path.partition(".")
        native = self.result.data.get(group, {}).get(device_id)
        if key == "id" or native is None:
            return False
        entry = {key: value}
        self._drop_meaningless(path, native.get("type", DEFAULT_KIND.get(group, "")), entry)
        return bool(entry)

    def _drop_meaningless(self, path: str, kind: str, native: dict[str, Any]) -> None:
        dropped = [k for k in ("outline_thickness",) if k in native]
        if kind == "drive":
            dropped += [k for k in ("position", "rotation") if k in native]
            velocity, ang_velocity = native.get("velocity"), native.get("ang_velocity")
            if ang_velocity and velocity is not None and not any(velocity):
                dropped.append("velocity")
            if ang_velocity == 0 and velocity is not None and any(velocity):
                dropped.append("ang_velocity")
        if kind == "infrared" and "bias" in native:
            dropped.append("bias")
        for key in dropped:
            del native[key]
        if dropped:
            log.debug("%s: %s: not used by SimMeR 2, ignored: %s", self.result.path, path, dropped)

    def _value(self, value: Any) -> Any:
        if isinstance(value, StandInDevice):
            return self.motor_ids.get(id(value), value)
        return _plain(value, self._value)


def original_protocol(namespace: dict[str, Any], data: dict[str, Any]) -> tuple[str, str]:
    """Which original wrote this config.py, and the protocol settings that follow from it.

    Fills ``protocol``, ``reply_bytes`` and ``lenient_commands`` in ``data`` unless the file
    sets them itself; returns the version and a sentence saying what replies will look like.
    """
    if "frame_start" in namespace or "frame_end" in namespace:
        version, why = "v1.2", "it sets frame_start/frame_end"
        data.setdefault("protocol", "framed")
    elif "maze_dim_x" in namespace:
        version, why = "v1.1", "it sets maze_dim_x and no frame_start"
        data.setdefault("protocol", "packed")
        data.setdefault("reply_bytes", 4)
    else:
        version, why = "v1.0", "it sets neither maze_dim_x nor frame_start"
        data.setdefault("protocol", "packed")
        data.setdefault("reply_bytes", 8)
    data.setdefault("lenient_commands", True)
    chosen = [name for name in ("protocol", "reply_bytes") if name in namespace]
    own = f", but it sets {' and '.join(chosen)}" if chosen else ""
    if data["protocol"] == "framed":
        start, end = data.get("frame_start", "["), data.get("frame_end", "]")
        replies = f"replies are framed text ({start}u0{end} -> {start}u0:15.45{end}); set "
        replies += "protocol = 'packed' to change"
    else:
        width = data.get("reply_bytes", 4)
        kind = "8-byte doubles" if width == 8 else "4-byte floats"
        replies = f"replies are {kind}; set reply_bytes to change"
    return version, f"looks like a SimMeR {version} config ({why}){own}: {replies}"


def _dict_entries(node: ast.expr | None) -> dict[str, tuple[ast.expr, ast.expr]]:
    """``{'key': value}`` literal -> key -> (key node, value node); {} for anything else."""
    if not isinstance(node, ast.Dict):
        return {}
    return {
        k.value: (k, v)
        for k, v in zip(node.keys, node.values, strict=True)
        if isinstance(k, ast.Constant) and isinstance(k.value, str)
    }


def _plain(value: Any, inner: Any = None) -> Any:
    """Configuration values as TOML-ready data: Vector2 -> [x, y], tuples -> lists."""
    inner = inner or _plain
    if isinstance(value, Vector2):
        return [_number(value.x), _number(value.y)]
    if isinstance(value, list | tuple):
        return [inner(v) for v in value]
    if isinstance(value, dict):
        return {str(k): inner(v) for k, v in value.items()}
    return value


def _number(value: float) -> float | int:
    return int(value) if value.is_integer() else value


def _user_module_path(cls: type, base_dir: Path) -> str | None:
    """Path of the file defining ``cls``, relative to the configuration, if it is a file."""
    file = template.module_file(cls)
    if file is None:
        return None
    return Path(os.path.relpath(file, base_dir.resolve())).as_posix()
