"""Documented API: ``wgpuviewer.reference.exact_hit`` (the reference lives in ``wgpuviewer.relief.reference``)."""

from wgpuviewer.relief.reference import Hit, exact_hit, sample_bilinear, uv_error_texels, view_dir_from_angles

__all__ = ["Hit", "exact_hit", "sample_bilinear", "uv_error_texels", "view_dir_from_angles"]
