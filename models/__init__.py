"""The learned dynamics model of the healthy vehicle: torch module, training, model files."""
