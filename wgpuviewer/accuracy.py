"""Documented API: ``wgpuviewer.accuracy.measure`` (it lives in ``wgpuviewer.relief.accuracy``)."""

from wgpuviewer.relief.accuracy import Accuracy, measure

__all__ = ["Accuracy", "measure"]
