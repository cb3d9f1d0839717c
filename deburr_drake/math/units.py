"""The length units a part's file may be written in (pure Python, so that
the configuration checks them without loading the mesh libraries)."""

__all__ = ["UNITS"]

#: metres per file unit
UNITS = {"m": 1.0, "mm": 1.0e-3, "cm": 1.0e-2, "in": 0.0254}
