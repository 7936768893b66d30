"""Figures and self-contained HTML reports built from result objects."""

from .modal_report import write_campbell_report, write_modal_report

__all__ = ["write_campbell_report", "write_modal_report"]
