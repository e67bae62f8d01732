//! mtec-model: error elements (ISO 230-1), error functions, machine chains, HTM and POE kinematics (exact and first-order), volumetric error.
