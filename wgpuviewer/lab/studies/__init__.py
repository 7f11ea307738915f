"""Studies: one folder each, one idea each (a paper's question, measured). A study folder exposes ``STUDY`` (the
``wgpuviewer.lab.harness.study.Study`` protocol: its command, options and run) in its ``__init__``; the harness finds
every folder here and the CLI registers each as a subcommand. A study has its own report (starting with the
harness's header) and its own smoke suite in the tests.

May import: ``wgpuviewer.core``, ``wgpuviewer.lab.harness``, ``wgpuviewer.relief``, the scene modules, ``maptools`` and
``wgpuviewer.lab.bench`` (the benchmark's views and height maps); a study never imports another study, and only the
CLI's discovery imports a study.
"""
