//! acr-plugins: sampler and filter plugins over the abstract rendering space (issue 4).
