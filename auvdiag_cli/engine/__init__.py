"""The diagnosis engine, in the order the data flows: ingest (read and resample), segments,
residuals (replay and g), detection (b and the alarm), hypotheses and active diagnosis,
substitution and closed-loop replay, the command and start checks, assembled by
`diagnosis`."""
