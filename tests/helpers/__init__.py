"""Shared test helpers (no tests here): project paths, hand-derived pinhole geometry, a DICOM
series writer and an object-space edge ground truth. Import them as ``tests.helpers.<module>``."""
