"""Input and output: files in, values out, and back — no simulation here.

- `records`: ground-motion records (PEER .AT2, two-column text, the packaged El Centro 1940 NS);
- `scenes_file`, `results_file`: the scenes CSV of a batch run and its results CSV;
- `tables`: CSV tables written exactly and atomically;
- `provenance`: how a result was made (versions, parameters, the command);
- `store`: a sweep's chunked store (xarray on Zarr), resumable and shared by Dask workers;
- `files`: output paths, atomic writes, exclusive locks.

The package imports none of them (the command line checks its output paths with `files` before
JAX is imported); the readers are public as `jaxrock.read_record`, `jaxrock.read_scenes`, ....
"""
