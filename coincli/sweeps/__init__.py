"""Basin sweeps: a plan checked before any work (:mod:`.plan`), the one engine that computes its
tiles (:mod:`.engine`) into a target (a store, :class:`coincli.io.basin_store.BasinStore`, or
memory, :class:`.memory.MemoryMap`) on an executor (threads or Dask, :mod:`.executors`), claims
that let several processes share one store (:mod:`.claims`), and the schema of what a basin
holds (:mod:`.schema`)."""
