"""The validation report: one HTML page per case plus an index and a JSON summary."""
from .validation import run_validation, write_report

__all__ = ["run_validation", "write_report"]
