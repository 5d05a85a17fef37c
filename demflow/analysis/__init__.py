"""Analysis on the common result tables (any engine): comparison, force statistics, micro-averages."""
from .compare import compare_curves, compare_distributions, compare_series, equilibrium
from .forces import (fit_exponential_tail, fit_mueth, fit_q_model, force_pdf, load_support, normalized_forces)
from .micro import average_stress, coordination_number, fabric_tensor

__all__ = ["compare_series", "compare_curves", "compare_distributions", "equilibrium", "normalized_forces",
           "force_pdf", "fit_exponential_tail", "fit_q_model", "fit_mueth", "load_support", "coordination_number",
           "fabric_tensor", "average_stress"]
