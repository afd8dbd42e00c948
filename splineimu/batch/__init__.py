"""Monte-Carlo batches: the ``vary:`` block and its draws (:mod:`splineimu.batch.vary`) and the Dask
plumbing (:mod:`splineimu.batch.cluster`); the job itself is :func:`splineimu.api.batch.run_batch`."""
