"""Model choice: several candidates fitted and compared by the held-out score
(:mod:`.compare`), and ``--model auto`` (:mod:`.auto`). The highest room but the package's entry
points (:mod:`roughbrdf.fitting.fit`, :mod:`roughbrdf.fitting.load`).
"""
