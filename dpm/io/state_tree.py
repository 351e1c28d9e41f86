"""An object graph as plain data: JSON text and numpy arrays, rebuilt without running code
from the file.

A checkpoint (:mod:`dpm.checkpoint`) stores a :class:`dpm.Simulation` this way. :func:`encode`
walks the graph as pickle does (each object's ``__reduce_ex__``, so ``__getstate__`` says
what is kept) but writes what it finds as JSON nodes; :func:`decode` builds the graph
again: containers and numbers directly, numpy arrays from datasets, objects by
``cls.__new__`` and their state (``__setstate__`` or the instance dictionary). Nothing in
the file is ever called: the file names classes, and only classes that this process
already trusts are built:

- classes of dpm itself, of a registered plugin's module, of the running script
  (``__main__``) or of a module of the user's own code it imported (a module already
  imported whose file is outside the standard library and the installed packages), and
  subclasses of a dpm class defined anywhere already imported;
- functions and classes referred to (a callback, a motion's profile) only from those
  same modules;
- numpy arrays of numbers, booleans or text; numpy scalars and dtypes; numpy random
  generators (their bit generator's name and state); paths, enums, slices, ranges.

A module is never imported on behalf of the file, except dpm's own. Anything else is
refused by name when the checkpoint is written (:class:`UnstorableError`) and when it is
read (:class:`ForbiddenError`). Unlike pickle, a crafted file can at most build objects
of these classes with wrong values.

Node forms (``#`` the node's number, for shared and cyclic references ``{"R": n}``):
``{"L": [...]}`` list, ``{"T": [...]}`` tuple, ``{"D": [[key, value], ...]}`` dict,
``{"S": [...]}`` set, ``{"FS": [...]}`` frozenset, ``{"F": "nan"}`` a non-finite float,
``{"B": base64}`` bytes, ``{"C": [re, im]}`` complex, ``{"A": name}`` an array stored as a
dataset, ``{"N": [dtype, shape, items]}`` a small array inline, ``{"G": [dtype, item]}`` a
numpy scalar, ``{"Y": dtype}`` a dtype, ``{"K": "module:name"}`` a class or function by
name, ``{"E": ["module:name", value]}`` an enum member, ``{"P": text}`` a path,
``{"RNG": [bit generator, state]}`` a numpy Generator, ``{"SL": [...]}`` a slice,
``{"RG": [...]}`` a range, ``{"O": ["module:name", args, state, list items, dict items]}``
an object.
"""

from __future__ import annotations

import base64
import copyreg
import enum
import functools
import importlib
import math
import os
import pathlib
import sys
from collections import OrderedDict, defaultdict, deque
from typing import Any

import numpy as np

from ..errors import ParameterError

#: arrays with fewer items stay inline in the JSON text
MIN_DATASET = 32
#: numpy bit generators a checkpoint may hold
BIT_GENERATORS = ("PCG64", "PCG64DXSM", "MT19937", "Philox", "SFC64")
#: built-in types that may be referred to by name (a defaultdict's factory)
_BUILTIN_TYPES = {t.__name__: t for t in (list, dict, set, tuple, int, float, str, bool,
                                           bytes, complex, frozenset, object)}
_PLAIN = (bool, int, str, type(None))


class UnstorableError(ParameterError):
    """An object of the scene cannot be stored as plain data."""


class ForbiddenError(ParameterError):
    """A stored state names a class or function this process does not trust."""


def _name(obj: Any) -> str:
    return f"{obj.__module__}:{obj.__qualname__}"


@functools.lru_cache(maxsize=1)
def _library_dirs() -> tuple[str, ...]:
    """Where the standard library and installed packages live (their code is never named
    by a checkpoint)."""
    import site
    import sysconfig

    dirs = {sysconfig.get_paths().get(k) for k in ("stdlib", "platstdlib", "purelib",
                                                    "platlib")}
    try:
        dirs.update(site.getsitepackages())
        dirs.add(site.getusersitepackages())
    except AttributeError:  # (a virtualenv's old site module)
        pass
    return tuple(os.path.realpath(d) + os.sep for d in dirs if d)


def _script_module(module: str) -> bool:
    """A module of the user's own code already imported (its file outside the standard
    library and the installed packages): a script's helper module."""
    mod = sys.modules.get(module)
    path = getattr(mod, "__file__", None)
    if not path:
        return False
    return not os.path.realpath(path).startswith(_library_dirs())


def _trusted_module(module: str, plugins: frozenset[str]) -> bool:
    return (module == "dpm" or module.startswith("dpm.") or module == "__main__"
            or module in plugins or _script_module(module))


def plugin_modules() -> frozenset[str]:
    """The modules of the registered plugins' classes (trusted as dpm's own)."""
    from ..plugins import registry

    reg = registry()
    mods = set()
    for table in reg.entries.values():
        for entry in table.values():
            mods.add(entry.cls.__module__)
    return frozenset(mods)


def _dpm_subclass(cls: type) -> bool:
    return any(_trusted_module(b.__module__, frozenset()) and b.__module__ != "__main__"
               for b in cls.__mro__[1:])


def _storable_class(cls: type, plugins: frozenset[str]) -> bool:
    return _trusted_module(cls.__module__, plugins) or _dpm_subclass(cls)


# ----------------------------------------------------------------- encode
class _Encoder:
    def __init__(self, where: str) -> None:
        self.where = where
        self.arrays: dict[str, np.ndarray] = {}
        self.memo: dict[int, int] = {}
        self.keep: list[Any] = []  # (holds what the memo's ids refer to)
        self.count = 0
        self.plugins = plugin_modules()
        self.path: list[str] = []

    def refuse(self, obj: Any, why: str) -> UnstorableError:
        at = "sim" + "".join(self.path)
        return UnstorableError(
            f"{self.where}: {at} is {type(obj).__module__}.{type(obj).__qualname__} "
            f"({why}); a checkpoint stores plain data only: objects of dpm's classes, of a "
            "registered plugin or of the running script (or subclasses of dpm's classes), "
            "numbers, text, containers and numpy arrays")

    def tag(self, obj: Any, node: dict[str, Any]) -> dict[str, Any]:
        self.memo[id(obj)] = self.count
        self.keep.append(obj)
        node["#"] = self.count
        self.count += 1
        return node

    def at(self, part: str, value: Any) -> Any:
        self.path.append(part)
        try:
            return self.encode(value)
        finally:
            self.path.pop()

    def encode(self, obj: Any) -> Any:
        if isinstance(obj, _PLAIN) and type(obj) in _PLAIN:
            return obj
        if type(obj) is float:
            return obj if math.isfinite(obj) else {"F": repr(obj)}
        ref = self.memo.get(id(obj))
        if ref is not None:
            return {"R": ref}
        t = type(obj)
        if t is list:
            node = self.tag(obj, {"L": None})
            node["L"] = [self.at(f"[{k}]", v) for k, v in enumerate(obj)]
            return node
        if t is tuple:
            return {"T": [self.at(f"[{k}]", v) for k, v in enumerate(obj)]}
        if t is dict:
            node = self.tag(obj, {"D": None})
            node["D"] = [[self.at(".key", k), self.at(f"[{k!r}]", v)] for k, v in obj.items()]
            return node
        if t is set or t is frozenset:
            key = "S" if t is set else "FS"
            node = self.tag(obj, {key: None})
            node[key] = [self.at("{}", v) for v in obj]
            return node
        if t is bytes:
            return {"B": base64.b64encode(obj).decode()}
        if t is complex:
            return {"C": [self.encode(obj.real), self.encode(obj.imag)]}
        if isinstance(obj, np.ndarray):  # (a subclass, as trimesh's, as a plain array)
            return self.array(obj if t is np.ndarray else obj.view(np.ndarray))
        if isinstance(obj, np.generic):
            if obj.dtype.kind not in "biufcUS":
                raise self.refuse(obj, "a numpy scalar of another kind")
            return {"G": [obj.dtype.str, self.encode(obj.item())]}
        if isinstance(obj, np.dtype):
            if obj.fields is not None or obj.kind not in "biufcUSb":
                raise self.refuse(obj, "a structured or object dtype")
            return {"Y": obj.str}
        if isinstance(obj, np.random.Generator):
            bg = obj.bit_generator
            if type(bg).__name__ not in BIT_GENERATORS:
                raise self.refuse(bg, "an unknown bit generator")
            return self.tag(obj, {"RNG": [type(bg).__name__, self.at(".state", bg.state)]})
        if isinstance(obj, pathlib.PurePath):
            return {"P": str(obj)}
        if isinstance(obj, enum.Enum):
            self.check_class(t, obj)
            return {"E": [_name(t), self.encode(obj.value)]}
        if t is slice:
            return {"SL": [self.encode(obj.start), self.encode(obj.stop), self.encode(obj.step)]}
        if t is range:
            return {"RG": [obj.start, obj.stop, obj.step]}
        if isinstance(obj, type):
            if obj.__module__ == "builtins" and obj.__name__ in _BUILTIN_TYPES:
                return {"K": f"builtins:{obj.__name__}"}
            self.check_class(obj, obj)
            return {"K": _name(obj)}
        if callable(obj) and hasattr(obj, "__qualname__") and hasattr(obj, "__module__") \
                and type(obj).__name__ in ("function", "builtin_function_or_method"):
            if not _trusted_module(obj.__module__ or "", self.plugins) \
                    or "<lambda>" in obj.__qualname__ or "<locals>" in obj.__qualname__:
                raise self.refuse(obj, f"the function {obj.__module__}.{obj.__qualname__}: "
                                  "functions are stored by name, from dpm, a plugin or the "
                                  "running script, at module level")
            return {"K": _name(obj)}
        if t in (OrderedDict, defaultdict, deque):
            return self.collection(obj)
        return self.instance(obj)

    def check_class(self, cls: type, obj: Any) -> None:
        if not _storable_class(cls, self.plugins) or "<locals>" in cls.__qualname__:
            raise self.refuse(obj, "a class from outside dpm, its plugins and the running "
                              "script, or defined inside a function")

    def array(self, a: np.ndarray) -> dict[str, Any]:
        if a.dtype.fields is not None or a.dtype.kind not in "biufcUSb":
            raise self.refuse(a, f"an array of dtype {a.dtype}")
        if a.dtype.kind in "biuf" and a.size >= MIN_DATASET:
            name = f"a{len(self.arrays)}"
            self.arrays[name] = a
            return self.tag(a, {"A": name})
        items = [self.encode(v) for v in a.ravel().tolist()] if a.dtype.kind in "fc" \
            else a.ravel().tolist()
        if a.dtype.kind == "S":
            items = [base64.b64encode(v).decode() for v in items]
        return self.tag(a, {"N": [a.dtype.str, list(a.shape), items]})

    def state(self, state: Any) -> Any:
        """An object's state; an instance dictionary's entries named as attributes."""
        if type(state) is not dict or not all(type(k) is str for k in state):
            return self.encode(state)
        node = self.tag(state, {"D": None})
        node["D"] = [[k, self.at(f".{k}", v)] for k, v in state.items()]
        return node

    def collection(self, obj: Any) -> dict[str, Any]:
        cls = type(obj)
        node = self.tag(obj, {"O": None})
        if cls is defaultdict:
            args = [self.at(".default_factory", obj.default_factory)]
            items = [[self.at(".key", k), self.at(f"[{k!r}]", v)] for k, v in obj.items()]
            node["O"] = [f"collections:{cls.__qualname__}", args, None, None, items]
        elif cls is OrderedDict:
            items = [[self.at(".key", k), self.at(f"[{k!r}]", v)] for k, v in obj.items()]
            node["O"] = ["collections:OrderedDict", [], None, None, items]
        else:
            node["O"] = ["collections:deque", [[], obj.maxlen], None,
                         [self.at(f"[{k}]", v) for k, v in enumerate(obj)], None]
        return node

    def instance(self, obj: Any) -> dict[str, Any]:
        try:
            rv = obj.__reduce_ex__(4)
        except Exception as exc:
            raise self.refuse(obj, f"it cannot be reduced: {exc}") from None
        if isinstance(rv, str):  # a module-level singleton
            raise self.refuse(obj, "a singleton stored by name")
        func, args = rv[0], rv[1]
        if func is copyreg.__newobj__:
            cls_, args = args[0], list(args[1:])
        elif func is copyreg.__newobj_ex__:
            cls_, pos, kw = args
            if kw:
                raise self.refuse(obj, "it is created with keyword arguments")
            args = list(pos)
        else:
            called = getattr(func, "__qualname__", func)
            raise self.refuse(obj, f"it is rebuilt by calling {called}")
        self.check_class(cls_, obj)
        node = self.tag(obj, {"O": None})
        state = rv[2] if len(rv) > 2 else None
        listitems = list(rv[3]) if len(rv) > 3 and rv[3] is not None else None
        dictitems = list(rv[4]) if len(rv) > 4 and rv[4] is not None else None
        node["O"] = [
            _name(cls_),
            [self.at(f"({k})", a) for k, a in enumerate(args)],
            None if state is None else self.state(state),
            None if listitems is None else [self.at(f"[{k}]", v)
                                            for k, v in enumerate(listitems)],
            None if dictitems is None else [[self.at(".key", k), self.at(f"[{k!r}]", v)]
                                            for k, v in dictitems],
        ]
        return node


def encode(obj: Any, where: str = "sim.checkpoint()") -> tuple[Any, dict[str, np.ndarray]]:
    """``obj`` as a JSON-able tree and the arrays it refers to by name (``{"A": name}``).
    Raises :class:`UnstorableError` naming the first object that cannot be stored, where
    it sits (``sim.backend.x[3]``) and why."""
    enc = _Encoder(where)
    tree = enc.encode(obj)
    return tree, enc.arrays


# ----------------------------------------------------------------- decode
class _Decoder:
    def __init__(self, arrays: Any, where: str) -> None:
        self.arrays = arrays
        self.where = where
        self.memo: dict[int, Any] = {}
        self.plugins = plugin_modules()

    def forbid(self, what: str) -> ForbiddenError:
        return ForbiddenError(f"{self.where}: the stored state names {what}; refused (a "
                              "checkpoint may build only dpm's classes, a registered "
                              "plugin's and the running script's)")

    def resolve(self, name: Any, kind: str) -> Any:
        if not isinstance(name, str) or ":" not in name:
            raise self.forbid(f"a {kind} {name!r} of no form 'module:name'")
        module, qual = name.split(":", 1)
        if module == "builtins" and kind == "name" and qual in _BUILTIN_TYPES:
            return _BUILTIN_TYPES[qual]
        if module == "collections" and kind == "class" and qual in ("OrderedDict",
                                                                    "defaultdict", "deque"):
            return {"OrderedDict": OrderedDict, "defaultdict": defaultdict,
                    "deque": deque}[qual]
        mod = sys.modules.get(module)
        if mod is None and (module == "dpm" or module.startswith("dpm.")):
            try:
                mod = importlib.import_module(module)
            except ImportError:
                mod = None
        if mod is None:
            raise ForbiddenError(
                f"{self.where}: the stored state needs {qual} from the module {module}, "
                "which this process has not imported; restart from the script (or with "
                "the plugin) that built the scene")
        obj: Any = mod
        for part in qual.split("."):
            if part.startswith("__") or part == "<locals>":
                raise self.forbid(f"{kind} {name}")
            obj = getattr(obj, part, None)
            if obj is None:
                raise ForbiddenError(f"{self.where}: the stored state needs {qual} from the "
                                     f"module {module}, which has no such name; restart "
                                     "from the script (or with the plugin) that built the "
                                     "scene")
        trusted = _trusted_module(module, self.plugins)
        if kind == "class":
            if not isinstance(obj, type) or not (trusted or _dpm_subclass(obj)) \
                    or getattr(obj, "__module__", None) != module:
                raise self.forbid(f"the class {name}")
        elif kind == "enum":
            if not (isinstance(obj, type) and issubclass(obj, enum.Enum)) or not (
                    trusted or _dpm_subclass(obj)):
                raise self.forbid(f"the enum {name}")
        elif not trusted or getattr(obj, "__module__", None) != module:
            raise self.forbid(f"the name {name}")
        return obj

    def decode(self, node: Any) -> Any:
        if node is None or isinstance(node, bool | int | float | str):
            return node
        if not isinstance(node, dict):
            raise self.forbid(f"a node of type {type(node).__name__}")
        if "R" in node:
            try:
                return self.memo[node["R"]]
            except (KeyError, TypeError):
                raise self.forbid(f"a reference {node['R']!r} to nothing") from None
        (key, value), *rest = [(k, v) for k, v in node.items() if k != "#"] or [(None, None)]
        if rest or key is None:
            raise self.forbid(f"a node with keys {sorted(node)}")
        num = node.get("#")
        out: Any
        if key == "L":
            out = self.remember(num, [])
            out.extend(self.decode(v) for v in value)
        elif key == "T":
            out = tuple(self.decode(v) for v in value)
        elif key == "D":
            out = self.remember(num, {})
            for k, v in value:
                out[self.decode(k)] = self.decode(v)
        elif key in ("S", "FS"):
            items = [self.decode(v) for v in value]
            out = self.remember(num, set(items) if key == "S" else frozenset(items))
        elif key == "F":
            if value not in ("nan", "inf", "-inf"):
                raise self.forbid(f"a float {value!r}")
            out = float(value)
        elif key == "B":
            out = base64.b64decode(value)
        elif key == "C":
            out = complex(self.decode(value[0]), self.decode(value[1]))
        elif key == "A":
            out = self.remember(num, self.dataset(value))
        elif key == "N":
            out = self.remember(num, self.inline(*value))
        elif key == "G":
            out = np.dtype(self.dtype(value[0])).type(self.decode(value[1]))
        elif key == "Y":
            out = np.dtype(self.dtype(value))
        elif key == "P":
            out = pathlib.Path(value)
        elif key == "E":
            out = self.resolve(value[0], "enum")(self.decode(value[1]))
        elif key == "RNG":
            name, state = value
            if name not in BIT_GENERATORS:
                raise self.forbid(f"the bit generator {name!r}")
            bg = getattr(np.random, name)()
            bg.state = self.decode(state)
            out = self.remember(num, np.random.Generator(bg))
        elif key == "SL":
            out = slice(*(self.decode(v) for v in value))
        elif key == "RG":
            out = range(*(int(v) for v in value))
        elif key == "K":
            out = self.resolve(value, "name")
        elif key == "O":
            out = self.instance(num, *value)
        else:
            raise self.forbid(f"a node of kind {key!r}")
        return out

    def remember(self, num: Any, obj: Any) -> Any:
        if num is not None:
            self.memo[num] = obj
        return obj

    def dtype(self, text: Any) -> np.dtype:
        try:
            dt = np.dtype(str(text))
        except TypeError:
            raise self.forbid(f"the dtype {text!r}") from None
        if dt.fields is not None or dt.kind not in "biufcUSb":
            raise self.forbid(f"the dtype {text!r}")
        return dt

    def dataset(self, name: Any) -> np.ndarray:
        try:
            data = self.arrays[str(name)][()]
        except KeyError:
            raise ParameterError(f"{self.where}: the array {name!r} of the stored state is "
                                 "missing from /arrays (a damaged or edited checkpoint)") from None
        a = np.ascontiguousarray(data)
        if a.dtype.kind not in "biufb":
            raise self.forbid(f"the array {name!r} of dtype {a.dtype}")
        return a

    def inline(self, dtype: Any, shape: Any, items: Any) -> np.ndarray:
        dt = self.dtype(dtype)
        if dt.kind == "S":
            items = [base64.b64decode(v) for v in items]
        elif dt.kind in "fc":
            items = [self.decode(v) for v in items]
        shape = tuple(int(s) for s in shape)
        if math.prod(shape) != len(items):
            raise self.forbid(f"an array of shape {shape} with {len(items)} items")
        return np.array(items, dtype=dt).reshape(shape)

    def instance(self, num: Any, name: Any, args: Any, state: Any, listitems: Any,
                 dictitems: Any) -> Any:
        cls = self.resolve(name, "class")
        if cls is defaultdict:
            out = self.remember(num, defaultdict(self.decode(args[0])))
        elif cls is deque:
            out = self.remember(num, deque([], args[1]))
        elif cls is OrderedDict:
            out = self.remember(num, OrderedDict())
        else:
            out = self.remember(num, cls.__new__(cls, *(self.decode(a) for a in args)))
        if state is not None:
            st = self.decode(state)
            setstate = getattr(type(out), "__setstate__", None)
            if setstate is not None:
                setstate(out, st)
            else:
                slots = None
                if isinstance(st, tuple) and len(st) == 2:
                    st, slots = st
                if st:
                    out.__dict__.update(st)
                for k, v in (slots or {}).items():
                    setattr(out, k, v)
        if listitems is not None:
            items = [self.decode(v) for v in listitems]
            out.extend(items) if hasattr(out, "extend") else [out.append(v) for v in items]
        if dictitems is not None:
            for k, v in dictitems:
                out[self.decode(k)] = self.decode(v)
        return out


def decode(tree: Any, arrays: Any, where: str = "dpm.restart()") -> Any:
    """The object graph of :func:`encode`'s ``tree``, its arrays read from ``arrays`` (a
    mapping of names to datasets or arrays). Raises :class:`ForbiddenError` naming the
    first class or function the state may not build, ParameterError for a damaged one."""
    dec = _Decoder(arrays, where)
    try:
        return dec.decode(tree)
    except RecursionError:
        raise ParameterError(f"{where}: the stored state is nested too deeply") from None
    except (ValueError, TypeError, IndexError, KeyError, AttributeError) as exc:
        if isinstance(exc, ParameterError):
            raise
        raise ParameterError(f"{where}: the stored state is damaged ({type(exc).__name__}: "
                             f"{exc})") from None
