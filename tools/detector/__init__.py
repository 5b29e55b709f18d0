"""Vehicle detector: data, model, losses, training, export and evaluation (see README.md)."""
