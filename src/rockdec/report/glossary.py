"""The words of an estimate's report (:mod:`rockdec.report.summary`), for ``rockdec estimate --help`` and the docs."""

__all__ = ["GLOSSARY"]

#: The words of the report (the command's ``--help`` and the docs' glossary show it).
GLOSSARY = """glossary:
  e          coefficient of restitution: the share of its angular velocity the block keeps
             at each impact (0 to 1)
  D_a        Random Decrement signature triggered where the angle peaks near the level
             a = 2 sigma_Y: the average free decay from rest (paper eq. 8)
  D_v        signature triggered where the angle crosses zero at the speed sigma_Ydot: the
             average motion through an impact (paper eq. 19)
  e_v        slope of D_v just after the impact over the slope just before (eq. 6);
             on clean records the least biased and least scattered
  e_g        from how fast all the peaks of D_a decay (eqs. 25, 7); the most biased
  e_0        from the first peak and first trough of D_a (eq. 26)
  e1 .. e4   from fits to D_a's first half cycle (eq. 27): e1 start and trough values,
             e2 slopes before and after the impact, e3 trough value and impact time,
             e4 impact and trough times
  raw        the estimator on your record, extrapolated to a zero trigger window (biased)
  corrected  the raw value with the bias removed, read off records simulated at known e
             with your record's length and sampling (the calibration)
  95 % interval  every e at which your raw value lies within the central 95 % of the raw
             values its simulated records give
  coverage   how often that interval held the true e on the calibration's records
             (near 95 % means the interval can be trusted)
  candidate  e_0, e4 and e_v: the estimators the report chooses from; of those with a
             value, an interval narrower than the calibrated range, and a coverage that
             holds (at least 95 % less the binomial error of the calibration's sets), the
             one whose calibration gives the narrowest interval at their common e (the
             median of their values) is reported and marked *
  record model  what besides e makes the record, and what the calibration simulates:
             the load (white, or low-pass with its corner in rocking frequencies), the
             sensor noise (in % of sigma_Y), the sensor filter and the rocking model; each
             measured off the record (with its standard error; used when detected) or
             declared
  sensor filter  a low-pass filter between the block and the record (a logger's
             anti-alias filter, a sensor's bandwidth, a smoothing): declared, the
             calibration filters its records alike; undeclared, the record is checked
             for one (the roll-off of its second differences; the impacts' velocity
             jumps spread over several samples, check `filtered`) and e declined when
             it shows one
  triggers   stretches of the record averaged into the signature, in the largest
             trigger window (more: less scatter)
  below / above the calibrated range  the raw value lies beyond what any calibrated e
             produces: e is outside that range, not estimated
  repaired   what was mended before the estimate: spikes replaced by the line through
             their neighbours, a drifting zero removed by a high-pass well below the
             rocking frequency; the calibration's records are mended alike (--no-repair: off)
  e_spread   free test: the standard deviation of the per-impact e about the block's e
  forced     shake test: e from every impact, the shaking's too, each flight fitted with
             the base's load in it (the other reading, impacts, is the free-decay tails')
  load gain  shake test: the base's load on the block as the flights read it over what
             the base's units and the block's angle say (1: they agree; beyond 1.2 refused)
  readings   shake test: every impact read twice, the base linear between its samples
             and held over each (a staircase); the interval is the union of both, and
             reading_gap the |log e| between their e
  flight_loss  free test: c of theta'' = -g sign(theta) - c theta' (1/s), the loss
             between impacts; fitted when its test finds it
  Housner's e  1 - 1.5 sin^2(atan(B/H)) of a block H high and B wide (--block H,B)
  sigma_Y    the rms angle of the record
  g          the block's restoring acceleration nu^2 theta_cr (rad/s^2, eq. 4), read
             off the record; not the acceleration of gravity"""
