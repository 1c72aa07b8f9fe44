"""A sweep's results to a Parquet file (pyarrow), one row group per finished chunk.

Columns: ``run_index`` (the row of the sweep's table), every numeric RodParams field
with its unit in the name (``eccentricity_m``, ``hub_inertia_kg_m2``, ...), the per-run
summary (``peak_deflection_m``, ``peak_time_s``, ``final_u_m``, ``final_v_m``,
``final_du_m_s``, ``final_dv_m_s``, ``final_theta_rad``, ``final_omega_rad_s``; NaN
where the run has no result) and ``status`` ('ok', 'invalid: ...', 'failed: ...').
Rows are in the order the chunks finished: sort by ``run_index`` for the table's order.
The schema's metadata key ``rotrod.sweep`` holds JSON with the profile, the duration,
the tolerance, the base parameters, the units and the command line.

The file is written as ``NAME.partial`` and renamed to NAME when closed, so a sweep that
dies never leaves a truncated file under the name asked for. pyarrow is imported here.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from rotrod_core.model.params import FIELD_UNITS
from rotrod_core.offline.sweep import PARAMETER_COLUMNS, RESULT_COLUMNS, RESULT_UNITS


def schema_columns() -> list:
    """(column, arrow type name) in file order."""
    return ([('run_index', 'int64')]
            + [(c, 'float64') for c in PARAMETER_COLUMNS.values()]
            + [(c, 'float64') for c in RESULT_COLUMNS.values()]
            + [('status', 'string')])


class SweepParquetWriter:
    """``with SweepParquetWriter(path, metadata) as w: w.write(chunk)`` (module docstring)."""

    def __init__(self, path, metadata: dict | None = None):
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            raise ValueError('writing a sweep needs pyarrow (pinned in constraints.txt)') \
                from None
        self.path = Path(path)
        if self.path.suffix.lower() != '.parquet':
            raise ValueError(f'the sweep file must end in .parquet, got {str(self.path)!r}')
        if not self.path.parent.is_dir():
            raise ValueError(f'output directory {str(self.path.parent)!r} does not exist')
        self.partial = self.path.with_name(self.path.name + '.partial')
        units = {PARAMETER_COLUMNS[k]: u for k, u in FIELD_UNITS.items()}
        units.update({RESULT_COLUMNS[k]: u for k, u in RESULT_UNITS.items()})
        meta = {'units': units, **(metadata or {})}
        types = {'int64': pa.int64(), 'float64': pa.float64(), 'string': pa.string()}
        self._pa = pa
        self.schema = pa.schema([(name, types[t]) for name, t in schema_columns()],
                                metadata={'rotrod.sweep': json.dumps(meta, default=str)})
        self._writer = pq.ParquetWriter(self.partial, self.schema)
        self.rows = 0

    def write(self, chunk) -> None:
        """Append one finished chunk (a :class:`rotrod_core.offline.sweep.ChunkResult`)."""
        columns = chunk.columns()
        arrays = []
        for name, _ in schema_columns():
            value = columns[name]
            arrays.append(self._pa.array(list(value) if name == 'status'
                                         else np.asarray(value)))
        self._writer.write_table(self._pa.Table.from_arrays(arrays, schema=self.schema))
        self.rows += len(chunk.index)

    def close(self) -> Path:
        """Finish the file and give it its name; returns the path."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None
            os.replace(self.partial, self.path)
        return self.path

    def __enter__(self):
        return self

    def __exit__(self, exc_type, *rest):
        if exc_type is None:
            self.close()
        elif self._writer is not None:
            self._writer.close()
            self._writer = None
        return False
