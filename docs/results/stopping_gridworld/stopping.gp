# Written by hbirl; run `gnuplot /tmp/re/stopping.gp` to redraw.
$curve << EOD
1 0.633333 0.618695
2 0.711111 0.71453
3 0.677778 0.765214
4 0.677778 0.848659
5 0.744444 0.859061
6 0.766667 0.880867
7 0.777778 0.886245
8 0.8 0.934867
9 0.833333 0.92595
10 0.855556 0.914537
11 0.9 0.943156
12 0.888889 0.940579
13 0.911111 0.948075
14 0.922222 0.962616
15 0.922222 0.973623
16 0.955556 0.971108
17 0.955556 0.989406
18 0.944444 0.984556
19 0.933333 0.990675
20 0.944444 0.976507
EOD
$stop0 << EOD
4 1
4 1
4 1
7 1
6 1
15 1
4 1
9 1
7 1
4 1
11 1
4 1
4 1
7 0
4 1
3 1
6 1
5 1
11 1
13 1
6 1
4 1
6 1
6 1
5 1
4 1
5 1
8 0
3 1
7 1
3 1
6 1
3 1
5 1
5 1
4 1
5 1
3 1
11 1
3 1
4 1
4 1
7 0
5 1
8 1
4 1
3 0
6 1
3 0
4 1
8 0
6 0
9 1
5 1
9 1
8 1
3 0
13 1
8 0
13 1
13 0
3 1
6 1
3 1
18 1
3 1
14 1
3 0
6 0
6 1
4 1
13 1
3 1
19 1
6 1
9 1
3 1
7 1
10 1
3 0
6 1
7 1
5 0
10 1
3 1
9 1
13 1
7 1
EOD
$stop1 << EOD
4 1
4 1
5 1
7 1
6 1
15 1
6 1
7 1
5 1
11 1
4 1
10 0
17 1
10 1
12 1
6 1
5 1
11 1
13 1
7 1
4 1
6 1
6 1
8 1
4 1
5 1
8 0
7 1
7 1
4 1
6 1
9 1
5 1
5 1
6 1
6 1
4 1
19 1
3 1
4 1
5 1
12 1
5 1
8 1
7 1
3 0
6 1
6 1
8 1
8 0
6 0
9 1
5 1
9 1
8 1
4 0
14 1
8 0
13 1
13 0
4 1
7 1
4 1
18 1
3 1
14 1
7 0
6 0
6 1
9 1
15 1
3 1
19 1
7 1
9 1
4 1
10 1
10 1
4 0
6 1
7 1
6 1
10 1
4 1
9 1
13 1
8 1
EOD
set terminal pngcairo size 1000,900 noenhanced font 'sans,11'
set output '/tmp/re/stopping.png'
set multiplot layout 2,1
set grid
set key bottom right
set xlabel 'demonstrations seen'
set yrange [0:1.05]
set title 'The Gridworld figure''s runs (|E| = 0, 1, 3, ..., 15 in turn, plausible eta) while watched: share right and mean confidence'
plot $curve using 1:2 with linespoints lw 2 pt 7 lc rgb '#1b9e77' title 'share right (tasks with >= n demonstrations)', $curve using 1:3 with linespoints lw 2 pt 5 lc rgb '#7570b3' title 'mean confidence'
set title 'Where the rule stopped (3 in a row): demonstrations at the stop'
set ylabel 'tasks'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.4
set key top right
plot $stop0 using ($1 + 0):(1) smooth frequency with boxes lc rgb '#d95f02' title 'p = 0.90', $stop1 using ($1 + 0.4):(1) smooth frequency with boxes lc rgb '#e7298a' title 'p = 0.95'
unset multiplot
set terminal svg size 1000,900 noenhanced font 'sans,11' background rgb 'white'
set output '/tmp/re/stopping.svg'
set multiplot layout 2,1
set grid
set key bottom right
set xlabel 'demonstrations seen'
set yrange [0:1.05]
set title 'The Gridworld figure''s runs (|E| = 0, 1, 3, ..., 15 in turn, plausible eta) while watched: share right and mean confidence'
plot $curve using 1:2 with linespoints lw 2 pt 7 lc rgb '#1b9e77' title 'share right (tasks with >= n demonstrations)', $curve using 1:3 with linespoints lw 2 pt 5 lc rgb '#7570b3' title 'mean confidence'
set title 'Where the rule stopped (3 in a row): demonstrations at the stop'
set ylabel 'tasks'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.4
set key top right
plot $stop0 using ($1 + 0):(1) smooth frequency with boxes lc rgb '#d95f02' title 'p = 0.90', $stop1 using ($1 + 0.4):(1) smooth frequency with boxes lc rgb '#e7298a' title 'p = 0.95'
unset multiplot
unset output
