% Cramér–Rao bound of Balda's seven eigenvalues (shared/reference/PAPER_NUMBERS.md) for the
% model FitPoleResidue fits: seven conjugate-pair modes and the origin correction h_o, 500 lines
% over 10–52 Hz, complex noise of standard deviation 1 % of |G| per line. Prints the bound for
% the same-sign residues of tests/unit/frequency/pole_residue_test.cc and searches the 315 pair's
% residues (strength k, ratio, phase of a7/a6) for the one that makes the pair identifiable.
%   octave -q tests/benchmarks/pole_residue_crb.m
1;
T = [-1.33 71.94; -18.24 70.53; -2.05 104.57; -2.28 110.53; -22.37 251.90; -19.84 315.03; -32.15 314.88];
s = T(:,1) + 1i*T(:,2);
p = 1i*linspace(2*pi*10, 2*pi*52, 500).';
h = [1.0 0.8 0.6 0.7 0.9 0.8 0.6].';

function sd = bound(s, a, p)
  G = zeros(size(p)); J = zeros(numel(p), 30);
  for v = 1:7
    d1 = 1./(p - s(v)); d2 = 1./(p - conj(s(v)));
    G += a(v)*d1 + conj(a(v))*d2;
    J(:,4*v-3) = a(v)*d1.^2 + conj(a(v))*d2.^2;
    J(:,4*v-2) = 1i*(a(v)*d1.^2 - conj(a(v))*d2.^2);
    J(:,4*v-1) = d1 + d2;
    J(:,4*v) = 1i*(d1 - d2);
  end
  J(:,29) = 1; J(:,30) = 1i;                      % h_o
  Jw = J ./ (0.01*abs(G));
  C = inv(2*real(Jw'*Jw));
  sd = [sqrt(diag(C)(4*(1:7)-3)) ./ abs(real(s)), sqrt(diag(C)(4*(1:7)-2)) ./ imag(s)] * 100;
end

a = 1i*real(s).*h;
sd = bound(s, a, p);
printf("same-sign residues: bound on Re s [%%] %s\n                    bound on Im s [%%] %s\n", ...
       sprintf("%.2f ", sd(:,1)), sprintf("%.3f ", sd(:,2)));
best = [inf 0 0 0];
for k = [1 2 4 8]
  for ratio = [0.5 1 1.5 2 3]
    for ph = 0:15:345
      b = a; b(6) = k*a(6); b(7) = ratio*b(6)*exp(1i*ph*pi/180);
      sd = bound(s, b, p);
      worst = max([sd(:,1)/5; sd(:,2)/0.5]);      % sigma over tolerance, worst of the 14
      if worst < best(1), best = [worst k ratio ph]; end
    end
  end
end
printf("best pair residues: a6 x %g, a7 = %g*a6*exp(i*%d deg): worst sigma/tolerance %.2f\n", best(2), best(3), best(4), best(1));
b = a; b(6) = 4*a(6); b(7) = -1.5*b(6);
sd = bound(s, b, p);
printf("the test's choice (a6 x 4, a7 = -1.5 a6): bound on Re s [%%] %s\n", sprintf("%.2f ", sd(:,1)));
printf("                                          bound on Im s [%%] %s\n", sprintf("%.3f ", sd(:,2)));
