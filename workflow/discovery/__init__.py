"""Model discovery: where the fitted friction model is wrong, why, and what fixes it.

Input per configuration: its measured log-decrement segments (rows of
``results/tables/segments.parquet``: ``configuration``, ``run``,
``velocity_amplitude_in_s``, ``zeta``, ``frequency_hz``, ``bearing_area_in2``).
Everything is computed from these; nothing is read from truth files.

Steps (docs/discovery.md states the rule with its numbers; the fits and the scatter are
:mod:`workflow.models.averaged_fit` and :mod:`workflow.models.configuration_data`):

1. **Scatter.** A smooth trend (robust cubic in ``log10 V``) through each curve; the
   scatter of the segments around it, per amplitude bin (1.4826 MAD), combined in
   quadrature with the averaged models' accuracy (``TOL_LN_ZETA``,
   ``TOL_REL_F``) gives every segment's standard uncertainty in ``ln zeta`` and in
   relative frequency. Residuals divided by it are the *normalised residuals*.
2. **Fits.** Every model of :mod:`workflow.models.averaged` is fitted by weighted least
   squares on both curves at once: a quasi-random (Sobol) global stage over the
   parameter box (log coordinates for scale parameters), then
   ``scipy.optimize.least_squares`` from the best distinct global points.
3. **Held-out error.** K-fold cross-validation over runs (interleaved in run
   order); with one run, contiguous amplitude blocks are held out. The error is the
   RMS normalised residual over the held-out segments, each quarter decade of
   amplitude weighted equally (:func:`workflow.discovery.heldout.amplitude_weights`).
4. **Discrepancy.** The best baseline's residuals, per half decade of amplitude
   and per curve: each run's mean residual in the bin, then mean and standard error
   over runs. A misfit is real where it is significant (Bonferroni-corrected t test,
   familywise 1 %) *and* larger than the models' accuracy. A linear trend of the
   runs' damping residuals with run order is tested the same way.
5. **Decision** (:func:`workflow.discovery.decision.decide`): ``none`` / a named cause / ``unknown``.
6. **Across configurations:** parameters linear in ``ln(bearing area)``, each
   configuration predicted from the others.

Modules: :mod:`~workflow.discovery.heldout` (cross-validation, held-out error),
:mod:`~workflow.discovery.misfit` (discrepancy tests), :mod:`~workflow.discovery.wording`,
:mod:`~workflow.discovery.decision`, :mod:`~workflow.discovery.microslip` (threshold
distribution), :mod:`~workflow.discovery.configuration` (one configuration),
:mod:`~workflow.discovery.campaign` (the document) and
:mod:`~workflow.discovery.diagnosis_files` (the files between rules).
"""
