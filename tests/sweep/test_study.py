def test_study_text_overrides_the_study_fields(tmp_path):
    from deburr_drake.sweep import load_study

    study = load_study(
        "studies/robustness.yaml",
        text="{name: robustness_localised, base: paper_localised, "
        "duration: 50.0}",
    )
    assert (study.name, study.base, study.duration) == (
        "robustness_localised",
        "paper_localised",
        50.0,
    )
    assert study.sample.count == 200 and len(study.sample.fields) == 17
