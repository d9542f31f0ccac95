"""Training, evaluation and deployment of policies, in layers (docs/layout.md lists the modules of each; a module
imports only its own layer and the ones before it, tests/test_layers.py); the soccer-only modules live in
policies.soccer, each in its layer:

    run files      config_io, config, soccer.config, run_dir, distributed
    checkpoints    checkpoints (the data-only formats)
    models         algorithms, latent_models, memory_models, hib, teacher_kl, students, warm_start, probe,
                   soccer.selfplay, brax_networks
    policy loading policy_io
    environments   environments, rsl_vecenv, soccer.steered
    backends       rsl_backend, brax_backend
    orchestration  training, distill, evaluate, eval_report, soccer.drill, navigate, nav_bench, export, convert,
                   average, tables, plots, bench_encoder
"""
