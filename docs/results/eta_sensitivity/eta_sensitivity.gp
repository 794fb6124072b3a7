# Written by hbirl; run `gnuplot /tmp/eta/eta_sensitivity.gp` to redraw.
$e3fixed << EOD
0 0 13.6503
1 0 2.2324
2 0 1.90742
3 0 2.38653
4 0 2.57392

0 1 52.1533
1 1 13.8989
2 1 0.19963
3 1 0.762419
4 1 8.48489

0 2 220.236
1 2 61.6939
2 2 0.573894
3 2 1.63452
4 2 8.31297

0 3 196.442
1 3 111.351
2 3 37.1511
3 3 0.39753
4 3 0.385503

EOD
$e3learned << EOD
0 0 2.2122
1 0 2.22511
2 0 0.359849
3 0 4.51999
4 0 4.54674

0 1 2.20658
1 1 0.360187
2 1 0.201177
3 1 0.173466
4 1 4.54762

0 2 0.513156
1 2 0.253087
2 2 1.65491
3 2 1.64946
4 2 4.54531

0 3 109.921
1 3 12.361
2 3 0.409972
3 3 0.175794
4 3 4.54511

EOD
$e7fixed << EOD
0 0 77.7408
1 0 6.8398
2 0 15.8188
3 0 14.2081
4 0 12.9728

0 1 203.862
1 1 74.9824
2 1 4.87025
3 1 9.95954
4 1 6.15351

0 2 224.61
1 2 128.488
2 2 26.0368
3 2 2.60805
4 2 4.30304

0 3 303.914
1 3 135.215
2 3 67.2081
3 3 2.66342
4 3 0.76458

EOD
$e7learned << EOD
0 0 10.2785
1 0 2.11032
2 0 3.30413
3 0 4.7042
4 0 0.766718

0 1 14.0539
1 1 5.09555
2 1 2.82976
3 1 4.42802
4 1 0.768449

0 2 35.8014
1 2 17.6706
2 2 0.273266
3 2 0.365701
4 2 0.438831

0 3 172.756
1 3 17.402
2 3 14.5602
3 3 1.69868
4 3 0.380362

EOD
set xtics ('0.2' 0, '0.4' 1, '0.6' 2, '0.8' 3, '1' 4)
set ytics ('0.4' 0, '0.6' 1, '0.8' 2, '0.95' 3)
set xlabel 'q: probability the labeller picks the true source'
set ylabel 'm: share of eta it gives its pick'
set cbrange [0:303.914]
set cblabel 'mean ILE'
set palette defined (0 '#f7fbff', 0.5 '#6baed6', 1 '#08306b')
set xrange [-0.5:4.5]
set yrange [-0.5:3.5]
unset key
set terminal pngcairo size 1000,840 noenhanced font 'sans,11'
set output '/tmp/eta/eta_sensitivity.png'
set multiplot layout 2,2 title 'ILE with a miscalibrated labeller (calibrated on the diagonal m = q)'
set title '|E| = 3, eta as stated'
plot $e3fixed using 1:2:3 with image, $e3fixed using 1:2:(sprintf('%.1f', $3)) with labels textcolor rgb '#d95f02'
set title '|E| = 3, eta learned'
plot $e3learned using 1:2:3 with image, $e3learned using 1:2:(sprintf('%.1f', $3)) with labels textcolor rgb '#d95f02'
set title '|E| = 7, eta as stated'
plot $e7fixed using 1:2:3 with image, $e7fixed using 1:2:(sprintf('%.1f', $3)) with labels textcolor rgb '#d95f02'
set title '|E| = 7, eta learned'
plot $e7learned using 1:2:3 with image, $e7learned using 1:2:(sprintf('%.1f', $3)) with labels textcolor rgb '#d95f02'
unset multiplot
set terminal svg size 1000,840 noenhanced font 'sans,11' background rgb 'white'
set output '/tmp/eta/eta_sensitivity.svg'
set multiplot layout 2,2 title 'ILE with a miscalibrated labeller (calibrated on the diagonal m = q)'
set title '|E| = 3, eta as stated'
plot $e3fixed using 1:2:3 with image, $e3fixed using 1:2:(sprintf('%.1f', $3)) with labels textcolor rgb '#d95f02'
set title '|E| = 3, eta learned'
plot $e3learned using 1:2:3 with image, $e3learned using 1:2:(sprintf('%.1f', $3)) with labels textcolor rgb '#d95f02'
set title '|E| = 7, eta as stated'
plot $e7fixed using 1:2:3 with image, $e7fixed using 1:2:(sprintf('%.1f', $3)) with labels textcolor rgb '#d95f02'
set title '|E| = 7, eta learned'
plot $e7learned using 1:2:3 with image, $e7learned using 1:2:(sprintf('%.1f', $3)) with labels textcolor rgb '#d95f02'
unset multiplot
unset output
