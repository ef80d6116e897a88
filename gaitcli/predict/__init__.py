"""Predictive gait by state dynamic optimization (Diss. ch. 5): the planar walking model, its NLP and the predict
stage (docs/architecture.md, "Predict"; the problem's readings and choices: docs/prediction.md)."""
