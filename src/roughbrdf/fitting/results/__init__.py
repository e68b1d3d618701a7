"""What a fit gives: :class:`~.result.FitResult` and :class:`~.result.ChannelFit`
(:mod:`.result`), the covariance and goodness of fit (:mod:`.statistics`), the text report
(:mod:`.report`), the plausibility checks (:mod:`.plausibility`: albedo, peak ratio) and the
physical ranges of parameters (:mod:`.physical`). Imports the problem and solver rooms.
"""
