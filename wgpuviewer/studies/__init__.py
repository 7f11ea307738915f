"""Studies: one folder each, one idea each (a seed paper's question, measured). A study has its own command, its
own report and its own smoke suite in the tests.

May import: ``wgpuviewer.core``, ``wgpuviewer.relief``, the scene modules, ``maptools`` and ``wgpuviewer.bench``
(the benchmark's views and height maps); a study never imports
another study, and only the CLI imports a study.
"""
