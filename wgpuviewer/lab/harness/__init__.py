"""The measurement harness that bench and every study share: a typed results table written and read back as CSV
(``table``), the plot context with atomic PNG saves (``plots``), the header every report.md starts with
(``header``), the stamp of a results folder (``stamp``), the smoke/full ``Suite`` base (``suite``), and the
``Study`` protocol with its discovery and its registration as ``wgpuviewer`` subcommands (``study``).

May import: ``wgpuviewer.core`` only, plus numpy and matplotlib. Studies are found by name at run time
(``study.discover``), never imported here.
"""
