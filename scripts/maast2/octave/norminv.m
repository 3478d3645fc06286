function x = norminv(p)
% Standard normal quantile, the one-argument form MAAST for ARAIM 2 calls
% (Matlab's Statistics Toolbox; not in core Octave). Same formula as
% Matlab's and Octave-statistics': -sqrt(2) * erfcinv(2 p).
x = -sqrt(2) .* erfcinv(2 .* p);
end
