//! mtec-nn: Neural error models on CPU: BPNN and CNN-LSTM. The only crate with the neural-network dependency.
