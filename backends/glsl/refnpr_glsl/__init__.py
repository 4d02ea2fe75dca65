"""refnpr_glsl: a GLSL (OpenGL 4.5 core, moderngl, headless EGL) backend that renders refnpr
conformance-kit cases from the kit alone. It never imports refnpr.

Run ``python -m refnpr_glsl KIT_DIR OUT_DIR [--only NAME ...] [--derivatives analytic|quad]``.
"""

__version__ = "0.1.0"
