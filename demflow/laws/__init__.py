"""Contact laws: the interface (:mod:`.base`) and its implementations, one module per family."""
from .base import LawFamily, law_energy_add, law_force, law_separate
from .linear import Linear, LinearParams

# every law family build() can select, in the order it tries them
FAMILIES = (Linear,)

__all__ = ["LawFamily", "Linear", "LinearParams", "FAMILIES", "law_force", "law_separate", "law_energy_add"]
