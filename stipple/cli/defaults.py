"""The library's choices and defaults that the options show in ``--help``, repeated here so that ``stipple --help``,
``stipple COMMAND --help`` and a usage error import neither numpy nor the method (they answer in a tenth of the
time). ``tests/test_commands.py`` checks every value against the module that owns it."""

# stipple.optimize
BETAS = ("hestenes-stiefel", "daniel")
SETTLE_WINDOW = 20
# stipple.halftone
INITS = ("stratified", "density", "uniform")
DEFAULT_SETTLE = 2e-3
MAX_POINTS = 20_000_000
MAX_ITERATIONS = 10**9
# stipple.nufft
BACKENDS = ("ducc0", "finufft", "cufinufft")
# stipple.video
FRAME_ITERATIONS = 12
# stipple.line
LINE_ITERATIONS = 400
# stipple.measures.plot_estimate (a common desktop plotter: mm/s pen down, mm/s pen up, seconds per lift)
DEFAULT_SPEED = 55.0
DEFAULT_TRAVEL_SPEED = 165.0
DEFAULT_LIFT = 0.3
# stipple.pipelines.pen
ORDERS = ("path", "progressive")
