"""Figures and self-contained HTML reports built from result objects."""

from .modal_report import write_campbell_report, write_modal_report
from .study_report import tooth_force_figure, write_study_report

__all__ = ["tooth_force_figure", "write_campbell_report", "write_modal_report",
           "write_study_report"]
