"""The lab: everything that measures the product, and nothing the product needs to run.

- ``harness/``: the results table, plots, report header, suites, the ``Study`` protocol, the generated-block type
  (``blocks``) and the results stamp (``stamp``: command, adapter, date, code fingerprint) bench and every study share;
- ``bench/``: the benchmark of GPU time against error;
- ``studies/NAME/``: one study of a paper's question each, found by the harness without a list;
- ``gpusuite.py``: ``./dev gpu-suite``, bench and the studies within one time budget on a lent GPU;
- ``docs.py``: ``wgpuviewer docs [--check]``, every generated block of README.md and docs/*.md from its one source;
- ``results.py``: ``wgpuviewer results [--check]``, every results folder fresh or stale against today's code.

The lab may import anything of the product (``core``, the scene modules, ``techniques``, ``relief``, ``maptools``);
nothing of the product (renderer, viewer, scenes, maptools, the Python API) imports the lab. Only the ``wgpuviewer``
command line reaches in, to register bench, the studies, ``docs`` and ``results`` as subcommands.
"""
