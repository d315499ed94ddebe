"""Arguments shared by tests that run the CLI."""

#: `bvhlab compare` as fast as it goes: one method, 5 frames and builds of an 8×8 image on the CPU,
#: no figures, no uniform-scene pass, no overlay timing (for tests about files and locks, not figures).
QUICK_COMPARE = [
    "--methods",
    "median",
    "--frames",
    "5",
    "--builds",
    "5",
    "--width",
    "8",
    "--height",
    "8",
    "--backend",
    "cpu",
    "--no-figures",
    "--no-uniform",
    "--overlay-backends",
    "none",
]
