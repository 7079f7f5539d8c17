// Placeholder: replaced by the Yu & Turk 2013 anisotropic surface.
