"""Snakemake's params checks without importing pandas: the same serialisations and stored
params as Snakemake's own, and pandas not imported for them (workflow.runtime.params_pandas).

Each check runs in a fresh interpreter: the replacement is process-wide, and whether
pandas gets imported can only be seen where nothing imported it before."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

# Snakemake's own methods are kept before the replacement and called last, since they
# import pandas.
CHECK = textwrap.dedent(
    """
    import json, sys
    import numpy as np
    from snakemake import persistence
    from snakemake.iocontainers import (
        InputFiles, Log, OutputFiles, Params, ResourceList, Snakemake, Wildcards,
    )
    from workflow.runtime.params_pandas import defer_pandas_import

    owner = persistence.PersistenceBase
    original_serialize = owner._serialize_param_pandas
    original_store = Snakemake._safely_store_params
    replaced = defer_pandas_import()
    defer_pandas_import()  # a second call changes nothing

    values = [8, 1.5, "fe", None, True, [1, "a"], (2, 3), {"order": 10, "band": [0.5, 2.0]},
              {1, 2}, b"x", range(3), np.arange(3.0), np.float64(2.5), object()]
    def params():
        return Params(fromdict={"decay": {"segment_cycles": 8}, "names": ["a", "b"],
                                "grid": np.arange(3.0), "x": 1.5})
    def job_object():
        return Snakemake(InputFiles(["in"]), OutputFiles(["out"]), params(), Wildcards(), 1,
                         ResourceList(), Log(), {}, "rule", None)

    class Persistence:
        _serialize_param_builtin = owner._serialize_param_builtin
    mine = [str(owner._serialize_param_pandas(Persistence(), v)) for v in values]
    stored = job_object()
    mine_stored = [list(stored._params_store), stored._params_types, list(stored.params.grid)]
    imported_for_them = "pandas" in sys.modules

    Snakemake._safely_store_params = original_store
    theirs = [str(original_serialize(Persistence(), v)) for v in values]
    stored = job_object()
    theirs_stored = [list(stored._params_store), stored._params_types, list(stored.params.grid)]
    print(json.dumps({"replaced": replaced, "imported": imported_for_them,
                      "same_serialized": mine == theirs,
                      "same_stored": repr(mine_stored) == repr(theirs_stored),
                      "pandas_now": "pandas" in sys.modules}))
    """
)


def run(code: str) -> dict:
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, check=False
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return json.loads(result.stdout.splitlines()[-1])


def test_params_are_serialised_and_stored_as_snakemake_does_without_importing_pandas():
    outcome = run(CHECK)
    assert outcome["replaced"] == [
        "PersistenceBase._serialize_param_pandas",
        "Snakemake._safely_store_params",
    ]
    assert not outcome["imported"]
    assert outcome["same_serialized"] and outcome["same_stored"]
    assert outcome["pandas_now"]  # Snakemake's own methods did import it


def test_pandas_params_are_still_recognised_once_pandas_is_imported():
    code = textwrap.dedent(
        """
        import json
        import pandas as pd
        from snakemake import persistence
        from snakemake.iocontainers import (
            InputFiles, Log, OutputFiles, Params, ResourceList, Snakemake, Wildcards,
        )
        from workflow.runtime.params_pandas import defer_pandas_import

        owner = persistence.PersistenceBase
        original = owner._serialize_param_pandas
        defer_pandas_import()
        class Persistence:
            _serialize_param_builtin = owner._serialize_param_builtin
        frame = pd.DataFrame({"a": [1.0, 2.0]})
        values = [frame, frame["a"], frame.index, 3]
        same = [owner._serialize_param_pandas(Persistence(), v) == original(Persistence(), v) for v in values]
        job = Snakemake(InputFiles([]), OutputFiles([]), Params(fromdict={"table": frame}), Wildcards(),
                        1, ResourceList(), Log(), {}, "rule", None)
        print(json.dumps({"same": same, "types": job._params_types,
                          "round_trip": job.params.table.equals(frame)}))
        """
    )
    outcome = run(code)
    assert outcome["same"] == [True, True, True, True]
    assert outcome["types"] == {"0": "pd.DataFrame"}
    assert outcome["round_trip"]
