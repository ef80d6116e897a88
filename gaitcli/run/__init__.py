"""Everything that executes stages: the registry entries, the pipeline and its configuration, trial folders,
prediction studies, batches, the workers they run on, and the comparison of output trees
(``docs/architecture.md``). Nothing here imports the command line (``cli.py``)."""
