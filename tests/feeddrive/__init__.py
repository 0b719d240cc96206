"""Tests of mtident.feeddrive: a package, so that test_identify and test_model here are not thermal's."""
