"""Documented API: ``wgpuviewer.probe.probe`` (the probe lives in ``wgpuviewer.relief.probe``)."""

from wgpuviewer.relief.probe import ProbeResult, probe

__all__ = ["ProbeResult", "probe"]
