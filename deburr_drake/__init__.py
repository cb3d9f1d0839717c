"""deburr_drake: Drake reproduction of Hsu & Fu, adaptive fuzzy hybrid position/force control of a deburring robot."""
