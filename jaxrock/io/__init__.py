"""Input and output: files in, values out, and back — no simulation here.

- `records`: ground-motion records (PEER .AT2, two-column text, the packaged El Centro 1940 NS);
- `scenes_file`, `results_file`: the scenes CSV of a batch run and its results CSV;
- `tables`: CSV tables written exactly and atomically;
- `provenance`: how a result was made (versions, parameters, the command), checkpoints;
- `files`: output paths, atomic writes, exclusive locks.
"""

from .records import el_centro, read_at2, read_record, read_two_column
from .scenes_file import read_scenes

__all__ = ["el_centro", "read_at2", "read_record", "read_two_column", "read_scenes"]
