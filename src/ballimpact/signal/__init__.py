"""Signal processing of a plate-voltage trace: baseline and decay, spikes, contact and its ends, the plate, checks."""
