"""mvgrasp_training: training code for mvgrasp's grasp-quality networks.

One typed TOML config per experiment (``training/configs/``), loaded with
:func:`mvgrasp_training.config.load_config`. Units follow the project's conventions (metres,
radians, seconds) and are spelled in key names where they are not obvious.
"""

from mvgrasp_training.config import (
    ConfigError,
    DataConfig,
    ExperimentConfig,
    TrainConfig,
    load_config,
    parse_config,
)

__all__ = [
    "ConfigError",
    "DataConfig",
    "ExperimentConfig",
    "TrainConfig",
    "load_config",
    "parse_config",
]
