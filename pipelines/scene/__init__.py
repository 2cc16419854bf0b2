"""Scene files: TOML in, a validated :class:`Scene` out.

A scene names its bodies (mesh, material, supports, reference points), the contact
interface and its law, the load and motion patterns with their time histories, the
procedure, and the *effects* it wants (``cof_evolution``, ``wear``). Validation reports every
problem at once, each naming its key, and nothing is built before the scene is valid.
Units: mm, N, MPa, t, s, mJ (see the README's scene reference).

Modules: :mod:`pipelines.scene.schema` (the keys, their types and meaning, :func:`validate`),
:mod:`pipelines.scene.checks` (the cross-reference checks that :func:`validate` runs: bodies,
materials, reference points, selections, effects, bolts, patterns), :mod:`pipelines.scene.writer`
(tables back to TOML text); this package reads scene files (``scene.base`` chains, overrides)
into a :class:`Scene`, and gives a scene back resolved (:func:`resolved_text`: one file that
stands for the whole chain). Typed views of its tables live with their users
(``pipelines.coupling.CouplingSettings``, ``contact.procedure.Procedure``), each with its
defaults in one place.
"""

from __future__ import annotations

import copy
import tomllib
from dataclasses import dataclass
from pathlib import Path

from pipelines.scene.schema import unknown_key, validate
from pipelines.scene.writer import dumps
from reduction.errors import InputError


@dataclass(frozen=True)
class Scene:
    """A validated scene: the parsed TOML tables and where it came from."""

    data: dict
    path: Path | None

    @property
    def name(self) -> str:
        return self.data["scene"]["name"]

    @property
    def effects(self) -> frozenset:
        return frozenset(self.data["scene"]["effects"])

    @property
    def dimension(self) -> int:
        return self.data["scene"]["dimension"]

    def section(self, name: str) -> dict:
        return self.data.get(name, {})


#: the byte-order mark Windows editors (Notepad) put before UTF-8 text: no part of the TOML
BOM = "\ufeff"


def parse(text: str, source: str = "scene", path: Path | None = None) -> Scene:
    """Parse and validate TOML text; raises :class:`InputError` listing every problem."""
    try:
        data = tomllib.loads(text.removeprefix(BOM))
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"{source}: not valid TOML: {error}") from None
    _refuse(validate(data, source) or _idle(data), source)
    return Scene(data, path)


def _idle(data: dict) -> list[str]:
    """A valid scene's procedure that would run no load cycle (:func:`checks.idle_procedure`)."""
    from pipelines.scene.checks import idle_procedure

    problem = idle_procedure(data)
    return [problem] if problem else []


def _refuse(problems: list[str], source) -> None:
    """One InputError saying every problem, if there is one."""
    if problems:
        raise InputError(f"{source}: " + ("\n  - ".join([f"{len(problems)} problem(s):"] + problems)
                                          if len(problems) > 1 else problems[0]))


#: the keys that say which kind a body's mesh table is: a scene that extends a base and gives a
#: mesh of the other kind replaces the base's mesh table instead of merging into it (a generated
#: block's dimensions mean nothing to a mesh file, and TOML cannot delete a key)
MESH_KINDS = ("generator", "file")


def _merged(base: dict, own: dict, path: tuple = ()) -> dict:
    """``own`` on top of ``base``: tables merge key by key, anything else is replaced; a body's
    ``mesh`` table of another kind (:data:`MESH_KINDS`) replaces the base's."""
    out = dict(base)
    for key, value in own.items():
        here = path + (key,)
        if isinstance(value, dict) and isinstance(base.get(key), dict) and not _other_mesh_kind(here, base[key], value):
            out[key] = _merged(base[key], value, here)
        else:
            out[key] = value
    return out


def _other_mesh_kind(path: tuple, base: dict, own: dict) -> bool:
    """Whether ``own`` is a body's mesh table (``bodies.NAME.mesh``) of another kind than ``base``."""
    if len(path) != 3 or path[0] != "bodies" or path[2] != "mesh":
        return False
    kind = [k for k in MESH_KINDS if k in own]
    return bool(kind) and not any(k in base for k in kind)


#: keys whose values are files, relative to the scene file that writes them ("*": any name)
FILE_KEYS = (("bodies", "*", "mesh", "file"), ("coupling", "histories"),
             ("mbs", "counterweight", "mesh_file"), ("mbs", "gas_pressure", "file"))


def _tables(node, keys: tuple):
    """The tables at ``keys`` (a path of names, "*" for every name) below ``node``."""
    if not keys:
        yield node
        return
    children = node.values() if keys[0] == "*" else [node.get(keys[0])]
    for child in children:
        if isinstance(child, dict):
            yield from _tables(child, keys[1:])


def _anchored(data: dict, folder: Path) -> dict:
    """``data`` with its relative file paths (:data:`FILE_KEYS`) made absolute from ``folder``: a
    base scene's files stay where the base is, whichever scene extends it."""
    for keys in FILE_KEYS:
        for table in _tables(data, keys[:-1]):
            value = table.get(keys[-1])
            if isinstance(value, str) and not Path(value).is_absolute():
                table[keys[-1]] = str(folder / value)
    return data


def _read(path: Path, seen: tuple = ()) -> dict:
    """The TOML of a scene file with its ``scene.base`` chain resolved (relative to the file; the
    base's own relative files relative to the base)."""
    if path.is_dir():
        raise InputError(f"scene file {path} is a folder: give a scene file (.toml) in it")
    if not path.exists():
        raise InputError(f"scene file {path} does not exist")
    if not path.is_file():
        raise InputError(f"scene file {path} is not a regular file (a device, pipe or socket): give a scene "
                         "file (.toml)")
    try:
        text = path.read_text(encoding="utf-8").removeprefix(BOM)
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"{path}: not valid TOML: {error}") from None
    except UnicodeDecodeError:
        raise InputError(f"scene file {path} is not a text file (a scene is TOML text, UTF-8)") from None
    except OSError as error:
        raise InputError(f"scene file {path} cannot be read ({error.strerror})") from None
    if not data:
        raise InputError(f"scene file {path} is empty{'' if not text.strip() else ' (comments only)'}: a scene "
                         "has at least [scene], [materials], [bodies] and [contact] (see examples/)")
    base = data.get("scene", {}).get("base") if isinstance(data.get("scene"), dict) else None
    if base is None:
        return data
    if not isinstance(base, str):
        raise InputError(f"{path}: 'scene.base' must be a string, the path of the scene file this one extends "
                         f"(relative to it), e.g. base = \"cylinder_on_plane.toml\"; got {base!r}")
    base_path = (path.parent / base).resolve()
    if base_path.is_dir() or not base_path.is_file():
        raise InputError(f"{path}: 'scene.base' names {base_path}, which "
                         + ("is a folder, not a scene file" if base_path.is_dir() else "does not exist"))
    if base_path in seen:
        raise InputError(f"{path}: 'scene.base' chain loops back to {base_path}")
    merged = _merged(_anchored(_read(base_path, seen + (base_path,)), base_path.parent), data)
    del merged["scene"]["base"]
    return merged


def tables(path: str | Path) -> dict:
    """The tables of a scene file (its ``scene.base`` chain resolved), not validated."""
    return _read(Path(path))


def load(path: str | Path, overrides: dict | None = None) -> Scene:
    """Read a scene file (and the file its ``scene.base`` extends); ``overrides``
    {"procedure.wear_cycles": 5, ...} replace values before validation."""
    path = Path(path)
    data = _read(path)
    for dotted in overrides or {}:
        problem = unknown_key(dotted)
        if problem:
            raise InputError(f"override {dotted} (set on top of {path}): {problem}")
    if overrides:
        apply_overrides(data, overrides)
    # a caller that sets the effects builds a model of its own (the validation job's patch tests)
    _refuse(validate(data, str(path)) or (_idle(data) if "scene.effects" not in (overrides or {}) else []), path)
    return Scene(data, path)


def resolved(scene: Scene) -> dict:
    """The tables a run of ``scene`` uses: its ``scene.base`` chain merged, its overrides applied,
    and every file it names (:data:`FILE_KEYS`) an absolute path, the scene file's own included,
    so that they mean the same read from any folder."""
    data = copy.deepcopy(scene.data)
    return _anchored(data, scene.path.resolve().parent) if scene.path is not None else data


def resolved_text(scene: Scene) -> str:
    """:func:`resolved` as TOML text: a scene file without a base that :func:`load` reads, from
    any folder, into the same tables (comments and layout of the original files are not kept)."""
    return dumps(resolved(scene))


def differences(old: dict, new: dict, prefix: str = "") -> list[str]:
    """The dotted keys whose values differ between two scenes' tables, named as overrides name
    them (an entry of an array of tables by its position: "loads.0.value")."""
    missing = object()
    keys = list(old) + [key for key in new if key not in old]
    found = []
    for key in keys:
        a, b, name = old.get(key, missing), new.get(key, missing), prefix + key
        if isinstance(a, dict) and isinstance(b, dict):
            found += differences(a, b, name + ".")
        elif (isinstance(a, list) and isinstance(b, list) and len(a) == len(b)
              and all(isinstance(entry, dict) for entry in a + b)):
            for index, (x, y) in enumerate(zip(a, b)):
                found += differences(x, y, f"{name}.{index}.")
        elif a != b:
            found.append(name)
    return found


def apply_overrides(data: dict, overrides: dict) -> None:
    """Set dotted keys in place, e.g. {"bodies.plane.mesh.contact_size": 0.1}.

    An entry of an array of tables ([[loads]], [[motions]]) is addressed by its position from
    0 or by its ``name``: "motions.0.value" or "motions.tangential.value". A key that runs
    into a value, or names no entry, is an InputError that says what is there."""
    for dotted, value in overrides.items():
        node, keys = data, dotted.split(".")
        for depth, key in enumerate(keys):
            where, last = ".".join(keys[:depth]) or "the scene", depth == len(keys) - 1
            if isinstance(node, list):
                node = _entry(node, key, dotted, where)
                if last:
                    raise InputError(f"{dotted}: an entry of {where} is a table; set one of its keys "
                                     f"({dotted}.KEY)")
            elif not isinstance(node, dict):
                raise InputError(f"{dotted}: {where} is a value ({node!r}), not a table with keys")
            elif last:
                node[key] = value
            else:
                node = node.setdefault(key, {})


def _entry(entries: list, key: str, dotted: str, where: str) -> dict:
    """The entry of an array of tables named by ``key``: its position from 0, or its name."""
    if not all(isinstance(entry, dict) for entry in entries):
        raise InputError(f"{dotted}: {where} is an array of values; give it whole ({where} = [...])")
    names = [entry.get("name") for entry in entries]
    if key.isdigit() and int(key) < len(entries):
        return entries[int(key)]
    if key in names:
        return entries[names.index(key)]
    named = f" or a name ({', '.join(map(str, names))})" if any(names) else ""
    raise InputError(f"{dotted}: {where} is an array of {len(entries)} table{'s' * (len(entries) != 1)}; "
                     f"address an entry by its position (0 to {len(entries) - 1}){named}, not {key!r}")
