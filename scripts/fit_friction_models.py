"""Rule fit_friction_models: Dahl and LuGre (plus zeta0 and the linear frequency)
fitted to one configuration's measured damping and frequency curves."""

from workflow.io.interim import read_campaign, read_configuration_diagnosis
from workflow.io.settings import DecaySettings, ModelSettings
from workflow.io.tables import read_table, write_json
from workflow.models.paper import (
    MIN_SEGMENTS_TO_FIT,
    averaged_fit_params,
    choose_modal_coordinate,
    fit_configuration,
)
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "fit_friction_models")
configuration = snakemake.wildcards.configuration
campaign = read_campaign(snakemake.input.campaign_settings)
modes = read_table(snakemake.input.modes).set_index("configuration")
segments = read_table(snakemake.input.segments)
mine = segments[segments["configuration"] == configuration]

if len(mine) < MIN_SEGMENTS_TO_FIT:
    # a configuration whose runs were all excluded: the others still get their fits
    document = {
        "models": {},
        "skipped": f"only {len(mine)} usable segments "
        f"(at least {MIN_SEGMENTS_TO_FIT} needed to fit); see runs.parquet",
    }
    log.warning("%s: models not fitted: %s", configuration, document["skipped"])
else:
    areas = {name: spec.bearing_area_in2 for name, spec in campaign.configurations.items()}
    coordinate = choose_modal_coordinate(modes["mode_hz"].dropna().to_dict(), areas)
    mode = modes.loc[configuration]
    models = ("dahl", "lugre")
    settings = ModelSettings(**snakemake.params.models)
    diagnosis = read_configuration_diagnosis(snakemake.input.diagnosis).diagnosis
    if diagnosis is not None:
        averaged = {model: diagnosis.fits[model].params for model in models}
    else:
        # the diagnosis skipped this configuration: fit the averaged models here
        averaged = {
            model: averaged_fit_params(model, mine, campaign.response.quantity, settings.seed)
            for model in models
        }
    document = fit_configuration(
        mine,
        models=models,
        sample_rate_hz=float(mode["sample_rate_hz"]),
        record_duration_s=float(mode["record_duration_s"]),
        band_hz=(float(mode["band_low_hz"]), float(mode["band_high_hz"])),
        response_quantity=campaign.response.quantity,
        coordinate=coordinate,
        analysis=DecaySettings(**snakemake.params.decay),
        settings=settings,
        averaged_params=averaged,
    )
    for model, fit in document["models"].items():
        log.info(
            "%s %s: rms ln zeta %.3f, rms rel f %.2e, %d ring-downs, %s",
            configuration,
            model,
            fit["rms_log_zeta"],
            fit["rms_rel_frequency"],
            fit["n_simulations"],
            fit["params"],
        )
write_json(snakemake.output[0], {"configuration": configuration, **document})
