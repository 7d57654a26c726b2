"""The library's choices and defaults that the options show in ``--help``, repeated here so that ``stipple --help``,
``stipple COMMAND --help`` and a usage error import neither numpy nor the method (they answer in a tenth of the
time). ``tests/test_commands.py`` checks every value against the module that owns it."""

# stipple.optimize
BETAS = ("hestenes-stiefel", "daniel")
SETTLE_WINDOW = 20
# stipple.halftone
INITS = ("stratified", "density", "uniform")
DEFAULT_SETTLE = 1.5e-3
# stipple.transforms
BACKENDS = ("ducc0", "finufft")
# stipple.video
FRAME_ITERATIONS = 20
# stipple.line
LINE_ITERATIONS = 400
