//! epsm-render
