"""The vehicle in the frequency domain: the linear model, frequency responses, ride on a track spectrum."""
