"""Long jobs on many logs that make or describe a model or a profile: train, calibrate,
relate, inspect, and drafting a profile from a log."""
