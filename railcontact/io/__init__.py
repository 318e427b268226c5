"""Output of solutions: strict JSON (:mod:`.jsonout`) and figures (:mod:`.plotting`)."""
