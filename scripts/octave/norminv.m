function x = norminv(p)
% Standard normal quantile, for Octave without the statistics package
% (scripts/availability_maast_compare.sh): Phi^-1(p) = -sqrt(2) erfcinv(2 p).
x = -sqrt(2) * erfcinv(2 * p);
end
