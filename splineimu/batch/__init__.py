"""Monte-Carlo batches: seeded variants of one scene on a Dask cluster."""
