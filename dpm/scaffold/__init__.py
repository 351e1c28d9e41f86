"""``dpm new-plugin NAME``: a new plugin package that passes its own tests at once.

The package (templates in ``dpm/scaffold/templates``, shipped with dpm) has a
``pyproject.toml`` with the entry point of group ``dpm``, a plugin module registering an
impact model composed from its own numba normal part and dpm's linear tangential part,
and a two-sphere shape, a kernels module, and tests that run :mod:`dpm.testing`'s
contract suites on both (runnable before installation: ``tests/conftest.py`` registers
the plugin module when the entry point is missing).

NAME is the distribution name: lower case letters, digits and single hyphens or
underscores between them, starting with a letter (``dpm-pebbles``); the import package is
NAME with hyphens as underscores (``dpm_pebbles``) and the classes are registered with the
prefix NAME without a leading ``dpm-`` (``pebbles_linear``, ``pebbles_dimer``). The
package goes into ``DIR/NAME``; an existing path there is refused (nothing is
overwritten).
"""

from __future__ import annotations

import importlib.util
import keyword
import re
from pathlib import Path

from ..errors import ParameterError

TEMPLATES = Path(__file__).resolve().parent / "templates"
_NAME = re.compile(r"^[a-z][a-z0-9]*(?:[-_][a-z0-9]+)*$")
#: (template, path in the package; PKG is replaced by the import name)
FILES = (("pyproject.toml.tmpl", "pyproject.toml"),
         ("README.md.tmpl", "README.md"),
         ("package/__init__.py.tmpl", "PKG/__init__.py"),
         ("package/kernels.py.tmpl", "PKG/kernels.py"),
         ("package/plugin.py.tmpl", "PKG/plugin.py"),
         ("tests/conftest.py.tmpl", "tests/conftest.py"),
         ("tests/test_plugin.py.tmpl", "tests/test_plugin.py"))


def names(name: str) -> dict[str, str]:
    """The distribution, import package, registration prefix and class prefix of NAME;
    :class:`ParameterError` if NAME is not allowed."""
    call = "dpm new-plugin"
    if not isinstance(name, str) or not _NAME.match(name):
        raise ParameterError(f"{call}: NAME={name!r} is not allowed; use lower case letters, "
                             "digits and single '-' or '_' between them, starting with a "
                             "letter (e.g. dpm-pebbles)")
    pkg = name.replace("-", "_")
    prefix = re.sub(r"^dpm[-_]", "", name).replace("-", "_")
    if pkg == "dpm" or prefix == "dpm" or keyword.iskeyword(pkg) or keyword.iskeyword(prefix):
        raise ParameterError(f"{call}: NAME={name!r} is not allowed; it gives the import name "
                             f"{pkg!r} / prefix {prefix!r}, which Python or dpm already use")
    if importlib.util.find_spec(pkg) is not None:
        raise ParameterError(f"{call}: NAME={name!r} is not allowed; its import name {pkg!r} "
                             "is an installed module already (choose another NAME)")
    cls = "".join(w.capitalize() for w in prefix.split("_"))
    return {"__DIST__": name, "__PKG__": pkg, "__PREFIX__": prefix, "__CLASS__": cls}


def render(template: str, subst: dict[str, str]) -> str:
    text = (TEMPLATES / template).read_text()
    for key, value in subst.items():
        text = text.replace(key, value)
    return text


def new_plugin(name: str, directory: str | Path = ".") -> Path:
    """Write the package NAME into ``directory/NAME``; return that path. Refuses an invalid
    NAME or an existing ``directory/NAME`` with :class:`ParameterError` before writing."""
    subst = names(name)
    root = Path(directory) / name
    if root.exists() or root.is_symlink():
        raise ParameterError(f"dpm new-plugin: {str(root)!r} exists already; nothing was "
                             "written (choose another NAME or --dir)")
    if Path(directory).exists() and not Path(directory).is_dir():
        raise ParameterError(f"dpm new-plugin: --dir={str(directory)!r} is not a directory")
    texts = {rel.replace("PKG", subst["__PKG__"]): render(tmpl, subst) for tmpl, rel in FILES}
    root.mkdir(parents=True)
    for rel, text in texts.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root
