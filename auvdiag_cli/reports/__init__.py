"""What the results look like to a reader: terminal text, JSON, time series and PDF pages,
formatted from results that are already computed (rendering never recomputes)."""
