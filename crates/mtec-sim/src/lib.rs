//! mtec-sim: The virtual machine: ground-truth errors, lumped thermal network, instrument models with noise, measurement scenarios.
