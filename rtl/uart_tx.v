// uart_tx: 8N1 UART transmitter with a valid/ready byte input.
//
// Assumptions: CLK_HZ / BAUD >= 4 (checked at elaboration in simulation and by FORMAL); the bit
// time is the rounded divisor, so rates that divide CLK_HZ exactly (12 MHz: 1 Mbaud = 12, 3 Mbaud = 4
// cycles a bit) have no error, others an error below 1 / (2 * divisor). The defaults are the board's
// clock and UART rate (common/regmap.json "link").
// Guarantees: tx_o idles high; each accepted byte leaves as start bit, eight data bits LSB first,
// one stop bit, every bit exactly CLKS_PER_BIT cycles; ready_o is high only when idle.
`resetall
`timescale 1ns / 1ps
`default_nettype none
`include "omniloc_regs.vh"

module uart_tx #(
    parameter integer CLK_HZ = `OMNILOC_BOARD_CLOCK_HZ,
    parameter integer BAUD   = `OMNILOC_UART_BAUD
) (
    input  wire       clk_i,
    input  wire       rst_i,
    input  wire [7:0] data_i,
    input  wire       valid_i,
    output wire       ready_o,
    output wire       tx_o
);

localparam integer CLKS_PER_BIT = (CLK_HZ + BAUD / 2) / BAUD;
localparam integer DIV_W = $clog2(CLKS_PER_BIT + 1);
localparam integer BIT_LAST_I = CLKS_PER_BIT - 1;
localparam [DIV_W-1:0] BIT_LAST = BIT_LAST_I[DIV_W-1:0];

reg [DIV_W-1:0] div_q;     // cycles left in the current bit
reg [3:0]       bits_q;    // bits left to send, including the stop bit
reg [8:0]       shift_q;   // {stop, data} still to send; LSB is on the line after the start bit
reg             tx_q;
reg             busy_q;

assign ready_o = !busy_q;
assign tx_o    = tx_q;

always @(posedge clk_i) begin
    if (rst_i) begin
        div_q   <= {DIV_W{1'b0}};
        bits_q  <= 4'd0;
        shift_q <= 9'h1FF;
        tx_q    <= 1'b1;
        busy_q  <= 1'b0;
    end else if (!busy_q) begin
        if (valid_i) begin
            busy_q  <= 1'b1;
            tx_q    <= 1'b0;                 // start bit
            shift_q <= {1'b1, data_i};
            bits_q  <= 4'd9;
            div_q   <= BIT_LAST;
        end
    end else if (div_q != {DIV_W{1'b0}}) begin
        div_q <= div_q - 1'b1;
    end else if (bits_q != 4'd0) begin
        tx_q    <= shift_q[0];
        shift_q <= {1'b1, shift_q[8:1]};
        bits_q  <= bits_q - 1'b1;
        div_q   <= BIT_LAST;
    end else begin
        busy_q <= 1'b0;                      // stop bit done
    end
end

`ifdef FORMAL
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
always @(*) if (!f_past_valid) assume(rst_i);   // start from reset
// Invariant for induction: the bits still to shift out above the next one are ones (the
// stop bit and the ones shifted in behind it), and an idle transmitter has nothing left.
integer fi;
reg f_shift_ok;
always @(*) begin
    f_shift_ok = 1'b1;
    for (fi = 0; fi < 9; fi = fi + 1)
        if (busy_q && bits_q != 4'd0 && fi >= bits_q - 1 && !shift_q[fi]) f_shift_ok = 1'b0;
end
always @(*) if (f_past_valid) begin
    assert(f_shift_ok);
    if (!busy_q) assert(bits_q == 4'd0 && tx_q);
    if (busy_q && bits_q == 4'd0) assert(tx_q);       // the stop bit
end
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i)) begin
        // Idle means the line is high.
        if (!busy_q) assert(tx_q);
        assert(bits_q <= 4'd9);
        assert(div_q <= BIT_LAST);
        // The line only changes at a bit boundary.
        if (busy_q && $past(busy_q) && $past(div_q) != {DIV_W{1'b0}}) assert(tx_q == $past(tx_q));
    end
    if (f_past_valid && $past(rst_i)) assert(tx_q && !busy_q);
end

// Each property reachable: a byte sent to its stop bit and the transmitter free again.
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        cover (!busy_q && $past(busy_q));
    end
end
`endif

endmodule

`default_nettype wire
