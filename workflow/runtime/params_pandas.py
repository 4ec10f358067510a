"""Snakemake's handling of rule params without importing pandas when no param can be
a pandas object.

Snakemake imports pandas in its own process in two places, to recognise params that
are pandas objects: when it decides whether a job's params changed since its outputs
were made (``Persistence._serialize_param_pandas``), and when it stores a script job's
params for the script (``Snakemake._safely_store_params``). Importing pandas takes
0.3-0.7 s of CPU; the first happens before anything else in a run with nothing to do,
the second before the first job starts. A value can only be an instance of a pandas
class once pandas has been imported, so both checks can ask an already imported pandas
and skip it otherwise: every param is serialised and stored exactly as before.
"""

from __future__ import annotations

import sys
from typing import Any

__all__ = [
    "serialize_param",
    "store_params_without_importing_pandas",
    "defer_pandas_import",
]


def serialize_param(persistence, value: Any) -> str | object:
    """``Persistence._serialize_param_pandas`` with pandas looked up, not imported."""
    pd = sys.modules.get("pandas")
    if pd is not None and isinstance(value, (pd.DataFrame, pd.Series, pd.Index)):
        return repr(pd.util.hash_pandas_object(value).tolist())
    return persistence._serialize_param_builtin(value)


def store_params_without_importing_pandas(store):
    """Wrap Snakemake's ``_safely_store_params``: while pandas is not imported, its
    ``import pandas`` fails as if pandas were absent, which that function handles by
    skipping its pandas checks. A Snakemake that no longer handles it gets the plain
    call. For the length of the call an import of pandas in another thread of
    Snakemake's process would fail as well; nothing in this workflow's Snakemake process
    imports pandas."""

    def wrapper(self, params):
        if sys.modules.get("pandas") is not None:
            return store(self, params)
        sys.modules["pandas"] = None  # `import pandas` raises ModuleNotFoundError
        try:
            return store(self, params)
        except ImportError:
            pass
        finally:
            if sys.modules.get("pandas", 0) is None:
                del sys.modules["pandas"]
        return store(self, params)

    wrapper.defers_pandas = True
    return wrapper


def defer_pandas_import() -> list[str]:
    """Make Snakemake's two params checks use pandas only if something imported it.

    Returns
    -------
    list of str
        The methods replaced; empty when this Snakemake has neither (a version whose
        internals moved), and the workflow runs as before.
    """
    from snakemake import persistence

    try:
        from snakemake.iocontainers import Snakemake
    except ImportError:
        Snakemake = None

    replaced = []
    for name in ("PersistenceBase", "Persistence"):
        owner = getattr(persistence, name, None)
        if hasattr(owner, "_serialize_param_pandas") and hasattr(owner, "_serialize_param_builtin"):
            owner._serialize_param_pandas = serialize_param
            replaced.append(f"{name}._serialize_param_pandas")
            break
    store = getattr(Snakemake, "_safely_store_params", None)
    if store is not None:
        if not getattr(store, "defers_pandas", False):
            Snakemake._safely_store_params = store_params_without_importing_pandas(store)
        replaced.append("Snakemake._safely_store_params")
    return replaced
