"""Code an agent runs: the digital protocol exported as dependency-free C99 or Python
(:mod:`.c`, :mod:`.python`), from a certified design (:mod:`.source`), written all or
nothing (:mod:`.run`)."""
