"""Names of settings' choices that the command line needs at start-up.

Kept apart from the numeric modules that act on them, so that building the CLI's
parser (``hesspipe --help``) loads no numpy; :mod:`hesspipe.identification.criteria` re-exports them.
"""

CRITERIA = ("paper", "df", "output")
"""Identification criteria: the paper's Eq. 10 PSD match, the describing function at the
forcing lines, the control time signal (:mod:`hesspipe.identification.criteria`)."""

DEFAULT_CRITERION = "df"
"""Chosen by measurement on the independent generator (benchmarks/bench_frf_identify.py, README)."""

OPTIMIZERS = ("apid", "scipy", "differential_evolution")
"""Optimizers of :func:`hesspipe.identification.fit.identify` (the paper's APID first)."""

DISPLAY_MEANINGS = {
    "compensatory": "the pilots saw only the error",
    "pursuit": "target and output apart: a feedforward on the target fitted in every model",
    "either": "not known: both fitted, the pursuit result kept where its feedforward is needed",
}
"""Each display in a few words, for reports that say which one a motion test assumed."""

DISPLAYS = tuple(DISPLAY_MEANINGS)
"""What the pilot saw: the error alone (the paper's task), or the target and the output apart,
where humans add a feedforward path on the target (the motion test's nuisance,
:data:`hesspipe.identification.motion_test.FEEDFORWARD`), or not known: "either" names motion
only when the test says so for both displays where the record shows that feedforward, and
elsewhere as the compensatory test does
(:data:`hesspipe.identification.motion_test.EITHER_FEEDFORWARD`)."""

DEFAULT_DISPLAY = "either"
"""The display assumed when a setting does not say: not known, since a recording rarely says
which display its pilot had, and a pursuit display's feedforward read as motion (README,
"Does the pilot need motion?"). On compensatory pilots the independent generator's motion
runs were named as often as with "compensatory"."""
