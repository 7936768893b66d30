"""The paper's studies (``gearmodal study NAME``) and the example model, scene and turbine files,
installed with the package as ``gearmodal.library`` (pyproject.toml maps this folder there), so
that an installed gearmodal finds them by name: ``gearmodal campbell 600kw``."""
