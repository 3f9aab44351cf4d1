//! epsm-ot
