function p = normcdf(x)
% Standard normal CDF, the one-argument form MAAST for ARAIM 2 calls
% (Matlab's Statistics Toolbox; not in core Octave). Same formula as
% Matlab's and Octave-statistics': 0.5 * erfc(-x / sqrt(2)).
p = 0.5 * erfc(-x ./ sqrt(2));
end
