//! mtec-thermal: Thermal error models: MLR, ridge with VIF and ridge-trace sensor selection, ambient-adaptive exponential feed-axis model; metrics.
