"""Surface EMG: channels named as muscles, band-pass, linear envelopes, on/off, cycles over strides (the emg
stage), and the comparison of estimated activations with them (Diss. 4.5.4)."""
