"""Matplotlib PDF reports: one dive (`dive`) and a fleet audit (`fleet`)."""
