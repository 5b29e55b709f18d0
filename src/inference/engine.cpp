// placeholder: filled by the engine implementation
