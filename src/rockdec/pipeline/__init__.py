"""The workflow's side: scenes (config and names), replicates and stored series, the steps
the rules call, where Dask computes, and the archive with its RO-Crate."""

__all__: list[str] = []
