"""The model-equivalence page, rendered from the capabilities table.

The table itself (feature → how each engine expresses it → measured consequence) is
:data:`demflow.engines.capabilities.FEATURES`; the deck writers consult the same table to refuse
what an engine cannot express.  This module is the page's stable entry point
(``demflow.report.validation`` calls :func:`as_html`).
"""
from __future__ import annotations

from .capabilities import FEATURES, as_html

__all__ = ["FEATURES", "as_html"]
