"""The plugin registry: one pluggy PluginManager over the entry-point group ``dpm``.

``registry()`` returns the loaded :class:`Registry`; ``lookup(kind, name)`` gives the class
registered under ``name`` or raises :class:`UnknownNameError` listing what is registered.
A plugin that fails to import or register (an exception, or ``sys.exit()`` or
``KeyboardInterrupt`` at import) is recorded in ``Registry.broken`` (shown by
``dpm plugins``) instead of breaking the others.

Two distributions registering one name of one kind is a conflict: the name stays listed,
and looking it up raises :class:`PluginConflictError` naming both (the other names of both
plugins work). ``DPM_BLOCK_PLUGINS`` (comma-separated distribution names, entry-point
names or ``dist:entry``) keeps plugins from loading; the built-ins cannot be blocked.
A run-time hook that raises stops the run with a :class:`PluginError` naming the plugin
(:func:`call_hook`).
"""

from __future__ import annotations

import importlib.metadata as md
from dataclasses import dataclass, field

import pluggy

from . import hookspecs
from .errors import DpmError, ParameterError, UnknownNameError

KINDS = ("shape", "boundary", "impact_model", "integrator", "backend", "motion", "region",
         "rolling_model")
_HOOK = {
    "shape": "dpm_register_shapes",
    "boundary": "dpm_register_boundaries",
    "impact_model": "dpm_register_impact_models",
    "integrator": "dpm_register_integrators",
    "backend": "dpm_register_backends",
    "motion": "dpm_register_motions",
    "region": "dpm_register_regions",
    "rolling_model": "dpm_register_rolling_models",
}
#: environment variable: plugins not to load (distribution or entry-point names)
BLOCK_ENV = "DPM_BLOCK_PLUGINS"
#: the source label of dpm's own plugin
BUILTIN = "dpm:builtin"
#: the distribution's name on the package index (``dpm`` there is an unrelated package);
#: the import name is ``dpm``
DISTRIBUTION = "dpm-granular"


class PluginError(DpmError, RuntimeError):
    """A plugin failed at run time (a hook raised): the message names the plugin."""


class PluginConflictError(PluginError, ParameterError):
    """Two plugins registered the same name of the same kind."""


@dataclass
class Entry:
    kind: str
    name: str
    cls: type
    source: str  # distribution name and entry point, or "<runtime>"
    version: str = ""  # the distribution's version ("" at run time)


@dataclass
class Registry:
    manager: pluggy.PluginManager
    entries: dict[str, dict[str, Entry]] = field(default_factory=lambda: {k: {} for k in KINDS})
    broken: list[tuple[str, str]] = field(default_factory=list)
    #: (kind, name) -> every entry that registered it, when more than one did
    conflicts: dict[tuple[str, str], list[Entry]] = field(default_factory=dict)
    blocked: list[str] = field(default_factory=list)
    versions: dict[str, str] = field(default_factory=dict)  # source -> version

    def add(self, kind: str, name: str, cls: type, source: str) -> None:
        if kind not in KINDS:
            raise ParameterError(f"register: kind={kind!r} is not one of {', '.join(KINDS)}")
        if not name or name != name.lower() or " " in name:
            raise ParameterError(f"register({kind}): name={name!r} must be lower_snake_case")
        new = Entry(kind, name, cls, source, self.versions.get(source, ""))
        old = self.entries[kind].get(name)
        if old is not None and old.cls is not cls:
            if source == "<runtime>" or old.source == source:
                self.entries[kind][name] = new  # a script (or the plugin) replaces its own
                return
            self.conflicts.setdefault((kind, name), [old]).append(new)
            return
        self.entries[kind][name] = new

    def lookup(self, kind: str, name: str, call: str = "") -> type:
        table = self.entries[kind]
        if isinstance(name, type):
            return name
        where = f"{call}: " if call else ""
        if name not in table and kind == "shape":
            from .shapes.library import names as grains
            from .shapes.library import shape_class

            grain = shape_class(name)
            if grain is not None:
                return grain
            known = ", ".join(sorted(table)) + "; library grains: " + ", ".join(grains())
            raise UnknownNameError(f"{where}unknown shape {name!r}; registered: {known}")
        if name not in table:
            known = ", ".join(sorted(table)) or "none"
            raise UnknownNameError(f"{where}unknown {kind.replace('_', ' ')} {name!r}; "
                                   f"registered: {known}")
        both = self.conflicts.get((kind, name))
        if both:
            who = " and by ".join(f"{_dist(e.source)} ({e.cls.__module__}.{e.cls.__qualname__})"
                                  for e in both)
            raise PluginConflictError(
                f"{where}{kind.replace('_', ' ')} {name!r} is registered by {who}; uninstall "
                f"one, or block one: {BLOCK_ENV}={_dist(both[-1].source)}")
        return table[name].cls

    def names(self, kind: str) -> list[str]:
        return sorted(self.entries[kind])

    def register_plugin(self, plugin: object, source: str) -> None:
        """Register a plugin object (module or instance) and collect its classes."""
        self.manager.register(plugin, name=source)
        for kind, hook in _HOOK.items():
            impl = getattr(plugin, hook, None)
            if impl is not None:
                impl(register=lambda n, c, _k=kind: self.add(_k, n, c, source))


def _dist(source: str) -> str:
    """The distribution name of a source label ``dist:entry``."""
    return source.split(":")[0]


_REGISTRY: Registry | None = None


def blocked_names() -> set[str]:
    """The plugin names ``$DPM_BLOCK_PLUGINS`` blocks."""
    import os

    return {w.strip() for w in os.environ.get(BLOCK_ENV, "").split(",") if w.strip()}


def registry(reload: bool = False) -> Registry:
    """Load (once) every plugin of the entry-point group ``dpm`` not blocked by
    ``$DPM_BLOCK_PLUGINS``."""
    global _REGISTRY
    if _REGISTRY is not None and not reload:
        return _REGISTRY
    pm = pluggy.PluginManager("dpm")
    pm.add_hookspecs(hookspecs)
    reg = Registry(pm)
    eps = sorted(md.entry_points(group="dpm"), key=lambda e: (e.name != "builtin", e.name))
    seen = set()
    block = blocked_names()
    for ep in eps:
        dist = ep.dist.name if ep.dist is not None else "?"
        # (the built-ins keep their label whatever the distribution is called)
        source = BUILTIN if ep.value == "dpm.builtin" else f"{dist}:{ep.name}"
        if source in seen:
            continue
        seen.add(source)
        if source != BUILTIN and block & {dist, ep.name, source}:
            reg.blocked.append(source)
            continue
        reg.versions[source] = ep.dist.version if ep.dist is not None else ""
        try:
            reg.register_plugin(ep.load(), source)
        except Exception as exc:  # a broken plugin must not break the others
            reg.broken.append((source, f"{type(exc).__name__}: {exc}"))
        except SystemExit as exc:  # nor end the program
            reg.broken.append((source, f"SystemExit: it called sys.exit({exc.code!r}) while "
                                       "loading"))
        except KeyboardInterrupt:
            reg.broken.append((source, "KeyboardInterrupt: it raised KeyboardInterrupt "
                                       "while loading"))
    if not reg.entries["impact_model"]:
        # running from a source tree without installed metadata: load the built-ins directly
        from . import builtin

        reg.versions[BUILTIN] = version()
        reg.register_plugin(builtin, BUILTIN)
    _REGISTRY = reg
    return reg


def register(kind: str, name: str, cls: type) -> None:
    """Register a class at run time (a script's own subclass), without an entry point."""
    registry().add(kind, name, cls, "<runtime>")


def version() -> str:
    """dpm's version (of the installed distribution; the source tree's otherwise)."""
    try:
        return md.version(DISTRIBUTION)
    except md.PackageNotFoundError:
        from . import __version__

        return __version__


def _rank_of(sim: object) -> int:
    """The MPI rank of the process running ``sim`` (0 on one process)."""
    rank = getattr(sim, "rank", None)
    if rank is None:
        from .parallel import rank as launched_rank

        return launched_rank()
    return int(rank)


def call_hook(reg: Registry, name: str, **kwargs: object) -> None:
    """Call every implementation of the run-time hook ``name`` (in pluggy's order, the
    last registered first), each with the arguments it names (``rank``, this process's
    MPI rank, given to those that ask for it); one that raises stops the caller with a
    :class:`PluginError` naming the plugin and the hook (the original exception
    chained)."""
    hook = getattr(reg.manager.hook, name)
    for impl in reversed(hook.get_hookimpls()):
        if "rank" in impl.argnames and "rank" not in kwargs:
            kwargs["rank"] = _rank_of(kwargs.get("sim"))
        try:
            impl.function(**{a: kwargs[a] for a in impl.argnames})
        except PluginError:
            raise
        except Exception as exc:
            raise PluginError(f"plugin {impl.plugin_name}: its {name} hook raised "
                              f"{type(exc).__name__}: {exc}") from exc
