# Stage 2: fit the ball model per ball type and write the session archive.


rule fit_ball:
    """Fit kB(0), AK, a, AC of one ball type with bootstrap intervals."""
    input:
        impacts_nc=result_path("work/impacts.nc"),
        session_yaml=raw_path("session.yaml"),
    output:
        fit=result_path("work/fit_{ball}.nc"),
    params:
        session_dir=session_dir,
        n_bootstrap=config["bootstrap"],
        seed=config["seed"],
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("fit_ball_{ball}"),
    benchmark:
        benchmark_path("fit_ball_{ball}")
    threads: 1
    script:
        "../scripts/fit_ball.py"


rule fit_session:
    """Fit every ball type of a small session in one job (config fit_batch_impacts): the
    same fits as rule fit_ball, without a process start-up per ball type."""
    input:
        impacts_nc=result_path("work/impacts.nc"),
        session_yaml=raw_path("session.yaml"),
    output:
        fits=result_path("work/fits.nc"),
    params:
        session_dir=session_dir,
        balls=ball_keys,
        n_bootstrap=config["bootstrap"],
        seed=config["seed"],
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("fit_session"),
    benchmark:
        benchmark_path("fit_session")
    threads: 1
    script:
        "../scripts/fit_session.py"


rule archive:
    """netCDF archive <session>.nc (impacts + fits + provenance) and parameters.csv."""
    input:
        snapshot=result_path("work/session.json"),
        session_yaml=raw_path("session.yaml"),
        impacts_nc=result_path("work/impacts.nc"),
        fits=fit_files,
    output:
        archive=result_path("{session}.nc"),
        parameters_csv=result_path("parameters.csv"),
    params:
        session_dir=session_dir,
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("archive"),
    threads: 1
    script:
        "../scripts/archive.py"
