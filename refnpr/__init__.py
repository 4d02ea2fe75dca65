"""refnpr: a CPU reference renderer for non-photorealistic shading."""

__version__ = "0.1.0"
