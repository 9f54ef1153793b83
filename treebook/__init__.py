"""treebook: learn, generate and reconstruct 3D trees."""
__version__ = "0.0.1"

from .tree import Tree, TreebookError
