"""Soccer-only training: the soccer section of a run's config (config: TrainConfig.soccer, its checks, and the
migration of configs that held its keys at the top level), self-play opponents (selfplay), a pilot's training game
in its vision student's camera game (steered) and `legged drill` (drill). Each module sits in the group of
`policies` its job belongs to (tests/test_layers.py): config with the run files, selfplay with the models,
steered with the environments, drill with the orchestration.
"""
