"""Runtime safety guards of the deburring cell (filled in below)."""

GUARDS_SYSTEM = "guards"
