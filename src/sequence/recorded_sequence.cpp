// placeholder: filled by the module's implementation
