"""The lab: everything that measures the product, and nothing the product needs to run.

- ``harness/``: the results table, plots, report header, suites and the ``Study`` protocol bench and every study share;
- ``bench/``: the benchmark of GPU time against error;
- ``studies/NAME/``: one study of a paper's question each, found by the harness without a list;
- ``gpusuite.py``: ``./dev gpu-suite``, bench and the studies within one time budget on a lent GPU;
- ``docs.py``: ``wgpuviewer docs [--check]``, every generated block of README.md and docs/*.md from its one source.

The lab may import anything of the product (``core``, the scene modules, ``techniques``, ``relief``, ``maptools``);
nothing of the product (renderer, viewer, scenes, maptools, the Python API) imports the lab. Only the ``wgpuviewer``
command line reaches in, to register bench, the studies and ``docs`` as subcommands.
"""
