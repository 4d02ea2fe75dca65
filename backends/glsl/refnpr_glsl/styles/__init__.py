"""Per-style shading passes: ``refnpr_glsl.styles.<name>.shade(gl, case, gbuffer, size)``."""
