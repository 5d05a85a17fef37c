"""The validation report: one HTML page per case plus an index and a JSON summary."""
from .validation import check_counts, run_validation, write_report

__all__ = ["check_counts", "run_validation", "write_report"]
