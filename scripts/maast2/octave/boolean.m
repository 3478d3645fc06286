function y = boolean(x)
% Matlab's boolean (logical conversion), which MAAST for ARAIM 2's
% compute_protection_level_v5.m calls; not in Octave.
y = logical(x);
end
