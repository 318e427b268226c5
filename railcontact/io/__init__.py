"""Output of solutions: strict JSON (:mod:`.jsonout`), a wheel-rail case's wheels with their
validity (:mod:`.wheels`) and figures (:mod:`.plotting`)."""
