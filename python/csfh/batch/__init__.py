"""Many runs of one scene: tasks with keys of everything that determines their result (tasks),
the resumable store of their results (store), and the executors that compute them serially, in
local processes or on a Dask cluster with identical results (executors)."""
