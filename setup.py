"""Packages found, not listed: every package below gaitcli/, and the sample trials and pipelines, which live at
the top of the repository and are installed inside the package (pyproject.toml's package-dir)."""

from setuptools import find_packages, setup

setup(packages=find_packages(include=["gaitcli", "gaitcli.*"]) + ["gaitcli.sample_trials", "gaitcli.pipelines"])
