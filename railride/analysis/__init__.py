"""Analysis of time histories: metrics, ride comfort, spectra and the labels of responses."""
