"""The plugin registry: one pluggy PluginManager over the entry-point group ``dpm``.

``registry()`` returns the loaded :class:`Registry`; ``lookup(kind, name)`` gives the class
registered under ``name`` or raises :class:`UnknownNameError` listing what is registered.
A plugin that fails to import or register is recorded in ``Registry.broken`` (shown by
``dpm plugins``) instead of breaking the others.
"""

from __future__ import annotations

import importlib.metadata as md
from dataclasses import dataclass, field

import pluggy

from . import hookspecs
from .errors import ParameterError, UnknownNameError

KINDS = ("shape", "boundary", "impact_model", "integrator", "backend")
_HOOK = {
    "shape": "dpm_register_shapes",
    "boundary": "dpm_register_boundaries",
    "impact_model": "dpm_register_impact_models",
    "integrator": "dpm_register_integrators",
    "backend": "dpm_register_backends",
}


@dataclass
class Entry:
    kind: str
    name: str
    cls: type
    source: str  # distribution name and entry point, or "<runtime>"


@dataclass
class Registry:
    manager: pluggy.PluginManager
    entries: dict[str, dict[str, Entry]] = field(default_factory=lambda: {k: {} for k in KINDS})
    broken: list[tuple[str, str]] = field(default_factory=list)

    def add(self, kind: str, name: str, cls: type, source: str) -> None:
        if kind not in KINDS:
            raise ParameterError(f"register: kind={kind!r} is not one of {', '.join(KINDS)}")
        if not name or name != name.lower() or " " in name:
            raise ParameterError(f"register({kind}): name={name!r} must be lower_snake_case")
        old = self.entries[kind].get(name)
        if old is not None and old.cls is not cls:
            self.broken.append((source, f"{kind} {name!r} already registered by {old.source}; "
                                        "the first registration is kept"))
            return
        self.entries[kind][name] = Entry(kind, name, cls, source)

    def lookup(self, kind: str, name: str, call: str = "") -> type:
        table = self.entries[kind]
        if isinstance(name, type):
            return name
        if name not in table:
            known = ", ".join(sorted(table)) or "none"
            where = f"{call}: " if call else ""
            raise UnknownNameError(f"{where}unknown {kind.replace('_', ' ')} {name!r}; "
                                   f"registered: {known}")
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


_REGISTRY: Registry | None = None


def registry(reload: bool = False) -> Registry:
    """Load (once) every plugin of the entry-point group ``dpm``."""
    global _REGISTRY
    if _REGISTRY is not None and not reload:
        return _REGISTRY
    pm = pluggy.PluginManager("dpm")
    pm.add_hookspecs(hookspecs)
    reg = Registry(pm)
    eps = sorted(md.entry_points(group="dpm"), key=lambda e: (e.name != "builtin", e.name))
    seen = set()
    for ep in eps:
        dist = ep.dist.name if ep.dist is not None else "?"
        source = f"{dist}:{ep.name}"
        if source in seen:
            continue
        seen.add(source)
        try:
            reg.register_plugin(ep.load(), source)
        except Exception as exc:  # a broken plugin must not break the others
            reg.broken.append((source, f"{type(exc).__name__}: {exc}"))
    if not reg.entries["impact_model"]:
        # running from a source tree without installed metadata: load the built-ins directly
        from . import builtin

        reg.register_plugin(builtin, "dpm:builtin")
    _REGISTRY = reg
    return reg


def register(kind: str, name: str, cls: type) -> None:
    """Register a class at run time (a script's own subclass), without an entry point."""
    registry().add(kind, name, cls, "<runtime>")
