function y = normcdf(x)
% Standard normal distribution function, for Octave without the
% statistics package: Phi(x) = erfc(-x / sqrt(2)) / 2.
y = 0.5 * erfc(-x / sqrt(2));
end
