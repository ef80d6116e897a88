"""The core below every stage: the trial container, events, validators, the stage registry."""
